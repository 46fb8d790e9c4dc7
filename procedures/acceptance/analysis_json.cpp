#include "procedures/acceptance/analysis_json.hpp"

#include <cmath>

namespace rig::acceptance {

namespace {
nlohmann::json num(std::optional<double> v) {
  return v && std::isfinite(*v) ? nlohmann::json(*v) : nlohmann::json(nullptr);
}
nlohmann::json term(const analysis::Term& t) {
  nlohmann::json j{{"value", num(t.value)}, {"unit", t.unit}};
  if (t.lo) j["lo"] = num(t.lo);
  if (t.hi) j["hi"] = num(t.hi);
  if (!t.value || !t.reason.empty()) j["reason"] = t.reason;
  return j;
}
}  // namespace

nlohmann::json dev_to_json(std::span<const analysis::DevPoint> dev) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& p : dev)
    a.push_back({{"m", p.m}, {"tau_s", p.tau_s}, {"n_terms", p.n_terms}, {"dev", p.dev}, {"lo", p.lo}, {"hi", p.hi},
                 {"edf", p.edf}, {"alpha", p.alpha}});
  return a;
}

nlohmann::json noise_terms_to_json(const analysis::NoiseTerms& nt) {
  return {{"Q", term(nt.Q)},
          {"N", term(nt.N)},
          {"B", term(nt.B)},
          {"tau_cp_s", num(nt.tau_cp_s)},
          {"K", term(nt.K)},
          {"R", term(nt.R)}};
}

nlohmann::json psd_to_json(const analysis::Psd& psd, const std::vector<analysis::Peak>& peaks) {
  nlohmann::json pk = nlohmann::json::array();
  for (const auto& p : peaks) pk.push_back({{"f_hz", p.f_hz}, {"psd", p.psd}, {"prominence_db", p.prominence_db}});
  return {{"f_hz", psd.f_hz}, {"psd", psd.psd}, {"unit", "g^2/Hz"}, {"peaks", pk}};
}

nlohmann::json loop_to_json(const plant::LoopFigures& f) {
  return {{"bandwidth_0p5_hz", f.bandwidth_0p5_hz},
          {"bandwidth_3db_hz", f.bandwidth_3db_hz},
          {"settling_time_s", f.settling_time_s}};
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
