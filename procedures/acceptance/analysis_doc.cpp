#include "procedures/acceptance/analysis_doc.hpp"

#include <algorithm>

namespace rig::acceptance {

nlohmann::json loop_to_json(const design::LoopFigures& f) {
  return {{"bandwidth_0p5_hz", f.bandwidth_0p5_hz},
          {"bandwidth_3db_hz", f.bandwidth_3db_hz},
          {"settling_time_s", f.settling_time_s},
          {"settling_band", f.settling_band},
          {"overshoot", f.overshoot},
          {"dc_gain", f.dc_gain},
          {"step", {{"t_s", f.step_t_s}, {"x", f.step_x}, {"y", f.step_y}}},
          {"freq", {{"f_hz", f.freq_hz}, {"mag_x", f.amp_x}, {"mag_y", f.amp_y}}}};
}

nlohmann::json analysis_document(const nlohmann::json& s) {
  nlohmann::json d{{"schema", "rig.analysis/1"}};
  nlohmann::json runs = nlohmann::json::array();
  if (s.contains("runs"))
    for (const auto& [k, r] : s["runs"].items()) runs.push_back(r);
  std::sort(runs.begin(), runs.end(), [](const auto& x, const auto& y) { return x["index"] < y["index"]; });
  d["runs"] = runs;
  if (s.contains("bias")) d["bias"] = s["bias"];
  if (s.contains("in_run")) d["in_run"] = s["in_run"];
  if (s.contains("raw")) d["raw"] = s["raw"];
  if (s.contains("analysis"))
    for (const auto& [k, v] : s["analysis"].items()) d[k] = v;
  if (s.contains("loop")) d["loop"] = s["loop"];
  if (s.contains("dut")) d["dut"] = s["dut"];
  return d;
}

}  // namespace rig::acceptance
