#include "procedures/acceptance/analysis_doc.hpp"


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

nlohmann::json analysis_document(const DutState& state) {
  const nlohmann::json s = to_json(state);
  nlohmann::json d{{"schema", "rig.analysis/1"}};
  nlohmann::json runs = nlohmann::json::array();
  for (const auto& [i, r] : state.runs) runs.push_back(s["runs"][std::to_string(i)]);  // std::map: by index
  d["runs"] = runs;
  for (const char* k : {"bias", "in_run", "raw", "loop", "dut"})
    if (s.contains(k)) d[k] = s[k];
  if (state.analysis)
    for (const auto& [k, v] : state.analysis->items()) d[k] = v;
  return d;
}

}  // namespace rig::acceptance
