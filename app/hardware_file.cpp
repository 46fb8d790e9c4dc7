#include "app/hardware_file.hpp"

#include <array>
#include <utility>

#include "firmware_link/connect.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/gpiod_lines.hpp"
#include "rig/modbus/table_client.hpp"
#include "rig/report/db_url.hpp"

namespace rig::cli {

namespace {

void check_rig(const toml::table& t) {
  cfg::check_keys(t, {"name"}, "rig");
  cfg::get_string(t, "name", std::string());
}

void check_history(const toml::table& t) {
  cfg::check_keys(t, {"url"}, "history");
  const std::string url = cfg::get_string(t, "url", std::string());
  // A URL this rig cannot open is the file's mistake, named at its line by every command that
  // reads the file (rig table did not look, and rig run named no line); a password in it masked.
  if (const toml::node* n = t.get("url"))
    if (const std::string why = history::url_problem(url); !why.empty())
      throw ConfigError(cfg::where(*n) + ": 'url' = '" + history::mask_password(url) + "': " + why);
}

// The one reader of [procedure]: the validation and apply_procedure_angles share it.
void read_procedure(const toml::table& t, double& u10_deg, double& u20_deg) {
  cfg::check_keys(t, {"u10_deg", "u20_deg"}, "procedure");
  // A mount's calibration is a pair: one angle alone would be checked against the other's
  // profile default, which the file does not show.
  if (t.contains("u10_deg") != t.contains("u20_deg"))
    throw ConfigError(cfg::where(t) + ": [procedure] gives " + (t.contains("u10_deg") ? "u10_deg" : "u20_deg") +
                      " without " + (t.contains("u10_deg") ? "u20_deg" : "u10_deg") +
                      ": a mount's calibrated angles are given together");
  u10_deg = cfg::get_number(t, "u10_deg", u10_deg, -360.0, 360.0);
  u20_deg = cfg::get_number(t, "u20_deg", u20_deg, -360.0, 540.0);
  acceptance::check_orientation_angles(t, u10_deg, u20_deg);
}

void check_procedure(const toml::table& t) {
  double u10 = 0, u20 = 180;
  read_procedure(t, u10, u20);
}

void check_gpio(const toml::table& t) { gpio::parse_gpio_config(t); }

// [dut]: the link's keys and values, and [dut.design] (the DUT type's loop model).
void check_dut(const toml::table& t) {
  link::check_dut_config(t);
  (void)acceptance::read_design_model(t);
}

constexpr std::array kSections = {
    HardwareSection{"rig", check_rig},
    HardwareSection{"table", modbus::check_table_config},
    HardwareSection{"dut", check_dut},
    HardwareSection{"gpio", check_gpio},
    HardwareSection{"procedure", check_procedure},
    HardwareSection{"history", check_history},
};

}  // namespace

std::span<const HardwareSection> hardware_sections() { return kSections; }

void validate_hardware(const toml::table& hw, std::initializer_list<std::string_view> required) {
  for (auto&& [k, v] : hw) {
    const HardwareSection* s = nullptr;
    for (const HardwareSection& c : kSections)
      if (c.name == k.str()) s = &c;
    if (!s) {
      std::string names;
      for (const HardwareSection& c : kSections) names += (names.empty() ? "" : ", ") + std::string(c.name);
      throw ConfigError(cfg::where(v) + ": unknown section '" + std::string(k.str()) +
                        "' in the hardware file (expected one of: " + names + ")");
    }
    s->check(*cfg::get_table(hw, k.str()));  // not a table: an error naming it
  }
  for (std::string_view r : required)
    if (!hw.contains(r)) {
      std::string names;
      for (std::string_view n : required) names += (names.empty() ? "[" : ", [") + std::string(n) + "]";
      throw ConfigError(cfg::where(hw) + ": no [" + std::string(r) + "] section (this command needs " + names + ")");
    }
}

toml::table load_hardware_file(const std::string& path, std::initializer_list<std::string_view> required) {
  toml::table hw = cfg::parse_file(path);
  validate_hardware(hw, required);
  return hw;
}

toml::table load_hardware_section(const std::string& path, std::string_view section) {
  toml::table hw = load_hardware_file(path, {section});
  return std::move(*hw.get_as<toml::table>(section));  // validated: present and a table
}

void apply_procedure_angles(const toml::table& hw, acceptance::Profile& p) {
  const toml::table* pr = cfg::get_table(hw, "procedure");
  if (pr) read_procedure(*pr, p.u10_deg, p.u20_deg);
  // [table] u10_deg / u20_deg are accepted so older files load, but never used: a mount's
  // calibration put there (where a profile keeps its angles) was measured at the profile's 0 and
  // 180 deg, silently (a technician's review). One that is not the angle the run turns to is refused.
  const toml::table* t = cfg::get_table(hw, "table");
  if (!t) return;
  for (const auto& [key, used] : {std::pair{"u10_deg", p.u10_deg}, {"u20_deg", p.u20_deg}})
    if (const toml::node* n = t->get(key); n && cfg::get_number(*t, key, used) != used)
      cfg::reject(*n, key,
                  fmt::format("[table]'s angles are not used: the run turns to {} at {:g}° ({}); a mount's angles go in "
                              "[procedure] u10_deg / u20_deg",
                              key[1] == '1' ? "U10" : "U20", used,
                              pr && pr->contains(key) ? "[procedure]'s" : "the profile's"));
}

}  // namespace rig::cli
