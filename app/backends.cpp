#include "app/backends.hpp"
#include "app/station_stop.hpp"

#include "firmware_link/connect.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "plant/emulated/world.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/gpiod_lines.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::cli {

Backends::Backends() = default;
Backends::~Backends() = default;
Backends::Backends(Backends&&) noexcept = default;
Backends& Backends::operator=(Backends&&) noexcept = default;

Devices Backends::devices() { return Devices{*table_ptr, *dut_ptr, *io_ptr, *clock_ptr, plant}; }

Backends make_emulated(const toml::table& plant_cfg, const std::string& serial) {
  Backends b;
  b.plant = "emulated";
  b.emulated = std::make_unique<plant::EmulatedPlant>(plant_cfg, serial);
  b.clock_ptr = &b.emulated->clock();
  b.table_ptr = &b.emulated->table();
  b.dut_ptr = &b.emulated->dut();
  b.io_ptr = &b.emulated->io();
  return b;
}

Backends make_hardware(const toml::table& hw, acceptance::Profile& p, const std::string& table_id) {
  // Configuration before devices: a mistake in any section (drive map included) is exit 2
  // naming the file, not hidden behind a device that cannot be opened.
  validate_hardware(hw, kRunSections);
  apply_procedure_angles(hw, p);
  Backends b;
  b.plant = "hardware";
  b.clock = std::make_unique<RealClock>();
  b.clock_ptr = b.clock.get();
  // [dut.design]: the DUT type's loop, the loop figures' labelled fallback without a loop test
  // (checked with the whole hardware file before any device opens: app/hardware_file).
  p.design_model = acceptance::read_design_model(*cfg::get_table(hw, "dut", true));
  // GPIO first: the e-stop watch must be live before anything moves.
  b.io = gpio::connect_gpio(*cfg::get_table(hw, "gpio", true));
  b.io_ptr = b.io.get();
  // A `rig table stop` from this station during a move ends the run as the operator's abort.
  const toml::table& table = *cfg::get_table(hw, "table", true);
  b.table = std::make_unique<StationStoppableTable>(modbus::connect_table(table, *b.clock), table_id);
  b.table_ptr = b.table.get();
  b.dut = link::connect_dut(*cfg::get_table(hw, "dut", true), *b.clock);
  b.dut_ptr = b.dut.get();
  return b;
}

}  // namespace rig::cli
