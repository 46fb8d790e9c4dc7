// Chooses the backends behind the seams at start-up (OpenHTF's plugs): the
// emulated plant in-process, or real hardware described by a TOML file.
#pragma once
#include <memory>
#include <string>

#include <toml++/toml.h>

#include "app/hardware_file.hpp"
#include "procedures/acceptance/profile.hpp"
#include "rig/executive/executive.hpp"

namespace rig::plant {
class EmulatedPlant;
}

namespace rig::cli {

struct Backends {
  std::string plant;  // "emulated" | "hardware"
  std::unique_ptr<plant::EmulatedPlant> emulated;
  std::unique_ptr<Clock> clock;
  std::unique_ptr<RotaryTable> table;
  std::unique_ptr<DutLink> dut;
  std::unique_ptr<RigIo> io;
  std::shared_ptr<void> unopened;  // make_unopened's stand-in behind all four seams
  Clock* clock_ptr = nullptr;
  RotaryTable* table_ptr = nullptr;
  DutLink* dut_ptr = nullptr;
  RigIo* io_ptr = nullptr;

  Backends();
  ~Backends();
  Backends(Backends&&) noexcept;
  Backends& operator=(Backends&&) noexcept;
  Devices devices();
};

// `plant_cfg`: the profile's [plant] section (plant/emulated/plant_config.hpp). `serial`
// (rig run --serial), when given, becomes the emulated DUT's serial: in emulation the operator
// names the DUT (CI jobs label passports that way), while on hardware the DUT's own serial is
// checked against it.
Backends make_emulated(const toml::table& plant_cfg, const std::string& serial = {});

// The devices of a hardware file (app/hardware_file.hpp, validated again here before the first
// device opens): [gpio] first (the e-stop watch), then [table] and [dut]; [procedure]
// u10_deg/u20_deg replace the profile's table angles with the mount's calibration. `table_id`:
// modbus::table_identity of [table], as the run's table lock took it.
Backends make_hardware(const toml::table& hw, acceptance::Profile& p, const std::string& table_id);

// No device opened, for a resume with nothing left to measure (every phase left computes from the
// run's records; Executive::without_devices): a technician finishing a verdict's ending need not
// have the DUT mounted, the table free or the station reachable, and nothing is powered or moved.
// Any command to these devices is a programming error (std::logic_error); a stop and a lamp are
// no-ops (nothing moved, no GPIO line held); the clock stands at `device_time_s`, where the run
// left it. `loop_test_refusal`: the DUT link's own refusal of the loop test
// (link::loop_test_refused_by), given as the link gives it; "" refuses the call as any other.
Backends make_unopened(const std::string& plant, double device_time_s, const std::string& loop_test_refusal);

}  // namespace rig::cli
