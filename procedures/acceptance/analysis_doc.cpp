#include "procedures/acceptance/analysis_doc.hpp"

#include <algorithm>

namespace rig::acceptance {

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
