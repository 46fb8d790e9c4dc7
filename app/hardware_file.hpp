// The hardware file (docs/hardware-config.md): one validation of every section and every key,
// shared by `rig run` (--dry-run included), `rig table`, `rig dut` and `rig capture import`,
// run before any device is opened, so a mistake is exit 2 naming FILE:LINE:COL, the key and
// the value, never a device error that hides it.
#pragma once
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "procedures/acceptance/profile.hpp"

namespace rig::cli {

// One top-level section: its name, and the reader that checks all its keys (known keys,
// types, ranges, cross-checks) without touching a device. Each reader lives beside the code
// that uses the values (rig/modbus for [table], firmware_link for [dut], rig/gpio for [gpio]),
// so what is checked is what is read. A new section is a row of hardware_sections(); a new
// key goes into its section's reader.
struct HardwareSection {
  std::string_view name;
  void (*check)(const toml::table& section);
};
std::span<const HardwareSection> hardware_sections();

// Parses `path` and validates it: unknown sections are errors, every section present is
// checked, and each of `required` must be present (rig run: table, dut, gpio; rig table:
// table; rig dut and rig capture import: dut).
toml::table load_hardware_file(const std::string& path, std::initializer_list<std::string_view> required);
void validate_hardware(const toml::table& hw, std::initializer_list<std::string_view> required);

// load_hardware_file(path, {section}) and that section taken out of it by move: its nodes keep
// their source (a toml++ copy drops it), so errors still name FILE:LINE:COL and a relative
// `[dut] dbc = ...` resolves from the hardware file's folder, as in `rig run` and `rig capture
// import`, not from the current directory.
toml::table load_hardware_section(const std::string& path, std::string_view section);

// The sections a hardware run needs.
inline const std::initializer_list<std::string_view> kRunSections = {"table", "dut", "gpio"};

// [procedure] u10_deg / u20_deg, the mount's calibrated angles, over the profile's.
void apply_procedure_angles(const toml::table& hw, acceptance::Profile& p);

}  // namespace rig::cli
