// The emulated plant in one process: the DUT's physics, the table emulator,
// the rig's GPIO lines and a simulated clock, stepped in lockstep by the
// consumer (every Clock::sleep_for and every sample read advances the world),
// so the 110-minute procedure runs in seconds and is bit-reproducible.
// Every seam goes through the shipped rig-side logic, once: the table through the
// real Modbus client over the emulator's register map (rig/modbus), the DUT through
// the real CAN client over an in-process bus to the firmware emulator, and the GPIO
// through the real e-stop/power logic (rig/gpio LineRigIo) over simulated lines.
#pragma once
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <toml++/toml.h>

#include "plant/emulated/dut_source.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/gpio.hpp"
#include "rig/core/table.hpp"
#include "rig/gpio/line_rig_io.hpp"

namespace rig::link {
class InProcessDutLink;
}

namespace rig::plant {

class TableEmulator;

// The profile's [plant] table's own keys (seed, dut, table, firmware; the removed `link` named),
// as EmulatedPlant checks them: for a command that reads a part of it without building the plant
// (`rig filter --dut PROFILE`, whose typo in [plant] went unsaid: a re-test). Throws ConfigError.
void check_plant_keys(const toml::table& plant_cfg);

class EmulatedPlant {
 public:
  // `plant_cfg` is the profile's [plant] table: seed, [plant.dut], [plant.table].
  // `serial`, when not empty, is the emulated DUT's serial (rig run --serial): in emulation the
  // operator names the DUT, on hardware the DUT's own serial is checked against it.
  explicit EmulatedPlant(const toml::table& plant_cfg, const std::string& serial = {});
  ~EmulatedPlant();

  SimClock& clock() { return clock_; }
  RotaryTable& table() { return *table_; }
  DutLink& dut();
  gpio::LineRigIo& io() { return *io_; }
  gpio::SimLines& lines() { return *lines_; }  // the "hardware" side of the rig's GPIO lines
  DutSource& dut_source() { return *dut_; }
  TableEmulator& table_emulator() { return *table_emu_; }

  // Test hooks: an e-stop edge at simulated time t; samples [from, from+count) never arrive.
  void trip_estop_at(double t_s) { estop_at_ = t_s; }
  void inject_drop(uint32_t from_seq, uint32_t count);
  // Per inject_drop, in order: how many of its samples fell while the DUT streamed (0: it never acted).
  std::vector<uint64_t> drop_hits() const;
  // An action run once when simulated time passes t (fault injection in tests).
  void at(double t_s, std::function<void()> action) { actions_.push_back({t_s, std::move(action)}); }
  // The DUT's next sequence number (free-running while powered).
  uint32_t next_seq() const;
  // DUT output samples generated so far (at the output rate, whether streamed or not).
  uint64_t samples_generated() const { return samples_; }

 private:
  class CountingSource;
  void advance(double dt_s);

  uint64_t samples_ = 0;  // declared before dut_: the counting wrapper refers to it

  SimClock clock_;
  std::unique_ptr<DutSource> dut_;
  std::unique_ptr<TableEmulator> table_emu_;
  std::unique_ptr<RotaryTable> table_;
  gpio::SimLines* lines_ = nullptr;  // owned by io_
  std::unique_ptr<gpio::LineRigIo> io_;
  std::unique_ptr<link::InProcessDutLink> link_;
  std::vector<std::pair<uint64_t, uint64_t>> drops_;
  std::optional<double> estop_at_;
  std::vector<std::pair<double, std::function<void()>>> actions_;
};

}  // namespace rig::plant
