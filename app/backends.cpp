#include "app/backends.hpp"

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

toml::table load_hardware_file(const std::string& path) {
  toml::table hw = cfg::parse_file(path);
  cfg::check_keys(hw, {"rig", "table", "dut", "gpio", "procedure", "history"}, "hardware file");
  cfg::get_table(hw, "table", true);
  cfg::get_table(hw, "dut", true);
  cfg::get_table(hw, "gpio", true);
  if (const toml::table* r = cfg::get_table(hw, "rig")) {
    cfg::check_keys(*r, {"name"}, "rig");
    cfg::get_string(*r, "name", std::string());
  }
  if (const toml::table* h = cfg::get_table(hw, "history")) {
    cfg::check_keys(*h, {"url"}, "history");
    cfg::get_string(*h, "url", std::string());
  }
  return hw;
}

Backends make_hardware(const toml::table& hw, acceptance::Profile& p) {
  if (const toml::table* pr = cfg::get_table(hw, "procedure")) {
    cfg::check_keys(*pr, {"u10_deg", "u20_deg"}, "procedure");
    p.u10_deg = cfg::get_number(*pr, "u10_deg", p.u10_deg, -360.0, 360.0);
    p.u20_deg = cfg::get_number(*pr, "u20_deg", p.u20_deg, -360.0, 540.0);
  }
  Backends b;
  b.plant = "hardware";
  b.clock = std::make_unique<RealClock>();
  b.clock_ptr = b.clock.get();
  // Configuration before devices: a [table] mistake (drive map included) is
  // exit 2 naming the file, not hidden behind a device that cannot be opened.
  modbus::check_table_config(*cfg::get_table(hw, "table", true));
  // [dut.design]: the DUT type's loop, the loop figures' labelled fallback without a loop test.
  p.design_model = acceptance::read_design_model(*cfg::get_table(hw, "dut", true));
  // GPIO first: the e-stop watch must be live before anything moves.
  b.io = gpio::connect_gpio(*cfg::get_table(hw, "gpio", true));
  b.io_ptr = b.io.get();
  b.table = modbus::connect_table(*cfg::get_table(hw, "table", true), *b.clock);
  b.table_ptr = b.table.get();
  b.dut = link::connect_dut(*cfg::get_table(hw, "dut", true), *b.clock);
  b.dut_ptr = b.dut.get();
  return b;
}

}  // namespace rig::cli
