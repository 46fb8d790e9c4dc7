#include "plant/dut/loop_figures.hpp"

#include "plant/dut/params.hpp"

namespace rig::plant {

design::LoopFigures loop_figures(const toml::table* dut_cfg, const FilterConfig& filter) {
  const DutParams p = load_dut_params(dut_cfg);
  return design::loop_figures(p.loop, p.regulator, filter);
}

}  // namespace rig::plant
