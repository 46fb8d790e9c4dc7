// The profile's [plant] section belongs to the emulated plant (docs/profiles.md): the
// procedure's profile parser allows the key and never reads it; the plant takes it from the
// same profile table (builtin text or file, its base merged in) and checks it itself.
#pragma once
#include <toml++/toml.h>

namespace rig::plant {

// The [plant] table of a profile table (a reference into it, so that errors keep their
// file:line:col: toml++ does not copy source positions); an empty table when the profile has
// none. A [plant] that is not a table is a ConfigError naming its place.
const toml::table& plant_section(const toml::table& profile);

// Checks [plant] as the emulated plant reads it -- seed, link, [plant.dut] against the DUT's
// parameters, [plant.table] against the table emulator's -- by building the plant from it, so
// `rig run --dry-run` reports a bad value with file:line:col before anything runs. Returns the
// emulated DUT's output rate, Hz, which a profile's rate_hz must match.
double validate_plant_section(const toml::table& plant);

}  // namespace rig::plant
