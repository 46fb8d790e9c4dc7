#include "plant/dut/loop_figures.hpp"

#include <cstdio>
#include <string>

#include "plant/dut/params.hpp"
#include "rig/core/errors.hpp"

namespace rig::plant {

design::LoopFigures loop_figures(const toml::table* dut_cfg, const FilterConfig& filter) {
  const DutParams p = load_dut_params(dut_cfg);
  design::LoopFigures f = design::loop_figures(p.loop, p.regulator, filter);
  // An unstable loop's step runs into inf and NaN: no figure of it means anything (one printed a
  // settling time of 17 ms and overshoot inf %, a code review).
  if (f.largest_pole >= 1) {
    char pole[32];
    std::snprintf(pole, sizeof pole, "%.6g", f.largest_pole);
    throw ConfigError(std::string("the DUT model's closed loop is unstable (a pole at |z| = ") + pole +
                      ", >= 1): it has no bandwidth or settling time; check its [plant.dut] loop and regulator");
  }
  return f;
}

}  // namespace rig::plant
