#include "plant/dut/loop_figures.hpp"

#include <cstdio>
#include <string>

#include "plant/dut/params.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {

design::LoopFigures loop_figures(const toml::table* dut_cfg, const FilterConfig& filter, std::string_view section) {
  const DutParams p = load_dut_params(dut_cfg, section);
  design::LoopFigures f = design::loop_figures(p.loop, p.regulator, filter);
  // An unstable loop's step runs into inf and NaN: no figure of it means anything (one printed a
  // settling time of 17 ms and overshoot inf %, a code review). Said with where the model comes
  // from and the values that set its gain (a re-test: it named neither).
  if (!f.stable()) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "the DUT model's closed loop is unstable (a pole at |z| = %.10g, > 1): it has no bandwidth or "
                  "settling time; its regulator: gain_a_per_v = %g, integral_corner_hz = %g, lead_zero_hz = %g, "
                  "lead_pole_hz = %g at loop_rate_hz = %g",
                  f.largest_pole, p.regulator.gain_a_per_v, p.regulator.integral_corner_hz, p.regulator.lead_zero_hz,
                  p.regulator.lead_pole_hz, p.loop.loop_rate_hz);
    throw ConfigError((!dut_cfg           ? std::string("the built-in DUT model: ")
                       : section.empty() ? cfg::where(*dut_cfg) + ": "
                                         : cfg::where(*dut_cfg) + ": [" + std::string(section) + "]: ") +
                      text);
  }
  return f;
}

}  // namespace rig::plant
