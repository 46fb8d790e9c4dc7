#include "procedures/acceptance/analysis_doc.hpp"
#include <algorithm>


namespace rig::acceptance {

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
  if (state.device_time_s) d["device_time_s"] = *state.device_time_s;
  return d;
}

}  // namespace rig::acceptance
