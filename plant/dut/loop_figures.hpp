// Closed-loop figures of the emulated DUT with a given output filter: its loop and
// regulator as its profile ([plant.dut] over plant/dut/default.toml) sets them, through
// the design model (design/loop_figures.hpp), so the figures come from the same loop
// that produces its output.
#pragma once
#include <string_view>

#include <toml++/toml.h>

#include "design/loop_figures.hpp"

namespace rig::plant {

// `dut_cfg` = the profile's [plant.dut] overrides (may be null; `section` what errors call
// it, load_dut_params), `filter` the output filter to evaluate (its rate is taken as the DUT's
// loop rate).
design::LoopFigures loop_figures(const toml::table* dut_cfg, const FilterConfig& filter,
                                 std::string_view section = "plant.dut");

}  // namespace rig::plant
