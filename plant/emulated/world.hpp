// The emulated plant in one process: the DUT's physics, the table emulator,
// the rig's GPIO lines and a simulated clock, stepped in lockstep by the
// consumer (every Clock::sleep_for and every sample read advances the world),
// so the 110-minute procedure runs in seconds and is bit-reproducible.
// The rig reaches the table through the real Modbus client logic over the
// emulator's register map (rig/modbus), and the DUT through the real CAN
// client over an in-process bus to the firmware emulator ([plant] link = "can",
// the default) or straight from the model (link = "direct", no frame codec).
#pragma once
#include <deque>
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

namespace rig::link {
class InProcessDutLink;
}

namespace rig::plant {

class TableEmulator;
class EmulatedPlant;

// The rig-side DUT link of the in-process plant: samples come straight from
// the DUT model (no frame codec), with the same sequence/gap accounting as the
// CAN link so gap handling is testable (inject_drop).
class DirectDutLink final : public DutLink {
 public:
  explicit DirectDutLink(EmulatedPlant& world) : world_(world) {}
  DutInfo info(const CancelToken& cancel) override;
  void start_stream(const CancelToken& cancel) override;
  void stop_stream() noexcept override;
  std::size_t read(std::span<Sample> out, const CancelToken& cancel) override;
  void set_filter(const FilterConfig& f, const CancelToken& cancel) override;
  FilterConfig get_filter(const CancelToken& cancel) override;
  LinkStats stats() const override { return stats_; }
  void reset_stats() override { stats_ = {}; }
  std::string describe() const override { return "emulated DUT (in-process, lockstep)"; }

 private:
  friend class EmulatedPlant;
  void deliver(const Sample& s);  // called by the world while streaming
  EmulatedPlant& world_;
  std::deque<Sample> queue_;
  bool streaming_ = false;
  std::optional<uint32_t> last_seq_;
  LinkStats stats_;
};

class EmulatedPlant {
 public:
  // `plant_cfg` is the profile's [plant] table: seed, [plant.dut], [plant.table].
  explicit EmulatedPlant(const toml::table& plant_cfg);
  ~EmulatedPlant();

  SimClock& clock() { return clock_; }
  RotaryTable& table() { return *table_; }
  DutLink& dut();
  SimGpio& io() { return io_; }
  DutSource& dut_source() { return *dut_; }
  TableEmulator& table_emulator() { return *table_emu_; }

  // Test hooks: an e-stop edge at simulated time t; samples [from, from+count) never arrive.
  void trip_estop_at(double t_s) { estop_at_ = t_s; }
  void inject_drop(uint32_t from_seq, uint32_t count);
  // An action run once when simulated time passes t (fault injection in tests).
  void at(double t_s, std::function<void()> action) { actions_.push_back({t_s, std::move(action)}); }
  // The DUT's next sequence number (free-running while powered).
  uint32_t next_seq() const;
  // DUT output samples generated so far (at the output rate, whether streamed or not).
  uint64_t samples_generated() const { return samples_; }

 private:
  friend class DirectDutLink;
  class CountingSource;
  void advance(double dt_s);

  uint64_t samples_ = 0;  // declared before dut_: the counting wrapper refers to it

  SimClock clock_;
  std::unique_ptr<DutSource> dut_;
  std::unique_ptr<TableEmulator> table_emu_;
  std::unique_ptr<RotaryTable> table_;
  SimGpio io_;
  DirectDutLink link_;
  std::unique_ptr<link::InProcessDutLink> can_link_;  // set when [plant] link = "can"
  std::vector<std::pair<uint64_t, uint64_t>> can_drops_;
  double sample_acc_ = 0;  // output periods owed to the DUT
  uint32_t seq_ = 0;
  std::optional<double> estop_at_;
  std::vector<std::pair<uint32_t, uint32_t>> drops_;
  std::vector<std::pair<double, std::function<void()>>> actions_;
};

}  // namespace rig::plant
