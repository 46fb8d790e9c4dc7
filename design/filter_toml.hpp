// The one reader of a [filter] table (the profile's [filter], the emulated DUT's
// [plant.dut.filter]):
//   preset  = "paper" (the paper's W_f(z)) | "none" (no sections, disabled) | "custom";
//   sections = [[b0, b1, b2, a1, a2], ...]   the cascade, with "custom" (preset may then be left out);
//   enabled = true | false                   after the preset;
//   rate_hz                                  where the caller's table has it (the profile's custom filter).
#pragma once
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "rig/core/filter_config.hpp"

namespace rig::design {

enum class RateKey { absent, allowed };

// Reads `t` onto `f`, which holds what applies without the table (a default, or a lower
// layer such as the DUT's compiled-in profile). Returns the preset read ("paper", "none",
// "custom"), or "" when the table names none and `f` keeps its sections. `ctx` names the
// table in errors; bad keys and values throw ConfigError with file:line:col.
std::string read_filter_table(const toml::table& t, std::string_view ctx, RateKey rate, FilterConfig& f);

}  // namespace rig::design
