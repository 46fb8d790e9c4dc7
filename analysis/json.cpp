#include "analysis/json.hpp"

#include <cmath>

namespace rig::analysis {

namespace {
using json = nlohmann::json;
namespace an = rig::analysis;

json num(std::optional<double> v) { return v && std::isfinite(*v) ? json(*v) : json(nullptr); }

// A term in its input units (tau in seconds) with its bounds, and the same in
// the passport's per-hour units where the term has them.
json term(const an::Term& t, double (*to_hours)(double) = nullptr, const char* hour_unit = "") {
  json j{{"value", num(t.value)}, {"unit", t.unit}};
  if (t.lo) j["lo"] = num(t.lo);
  if (t.hi) j["hi"] = num(t.hi);
  if (!t.reason.empty()) j["reason"] = t.reason;
  if (to_hours) {  // the unit also when the term has no value, so a reader can quote it
    j["per_hour"] = {{"value", t.value ? json(to_hours(*t.value)) : json(nullptr)}, {"unit", hour_unit}};
    if (t.lo) j["per_hour"]["lo"] = to_hours(*t.lo);
    if (t.hi) j["per_hour"]["hi"] = to_hours(*t.hi);
  } else if (to_hours && t.hi) {  // null with an upper limit
    j["per_hour"] = {{"value", nullptr}, {"unit", hour_unit}, {"hi", to_hours(*t.hi)}};
  }
  return j;
}
}  // namespace

json dev_to_json(std::span<const an::DevPoint> dev, bool bounds) {
  json a = json::array();
  for (const auto& p : dev) {
    if (bounds)
      a.push_back({{"m", p.m}, {"tau_s", p.tau_s}, {"n_terms", p.n_terms}, {"dev", p.dev}, {"lo", p.lo}, {"hi", p.hi},
                   {"edf", p.edf}, {"alpha", p.alpha}, {"edf_alpha", p.edf_alpha}});
    else  // nothing identified, nothing bounded: null, not a 0 that reads as measured
      a.push_back({{"m", p.m}, {"tau_s", p.tau_s}, {"n_terms", p.n_terms}, {"dev", p.dev}, {"lo", nullptr},
                   {"hi", nullptr}, {"edf", nullptr}, {"alpha", nullptr}, {"edf_alpha", nullptr}});
  }
  return a;
}

json long_tau_to_json(std::span<const an::LongTauPoint> pts, bool bounds) {
  json a = json::array();
  for (const auto& p : pts) {
    json j{{"m", p.m},         {"tau_s", p.tau_s}, {"n_terms", p.n_terms}, {"dev", p.dev},
           {"dev_raw", p.dev_raw}, {"lo", p.lo},   {"hi", p.hi},           {"edf", p.edf},
           {"alpha", p.alpha}, {"stride", p.stride}, {"estimator", p.estimator},
           {"edf_alpha", p.alpha}};  // the contract's field: no EDF guard here, the EDF is alpha's
    if (!bounds)  // as dev_to_json: nothing identified, nothing bounded
      for (const char* k : {"lo", "hi", "edf", "alpha", "edf_alpha"}) j[k] = nullptr;
    else if (!p.bounds_note.empty())  // no interval at this EDF: null, and why
      j["lo"] = j["hi"] = j["edf"] = nullptr, j["bounds_note"] = p.bounds_note;
    a.push_back(std::move(j));
  }
  return a;
}

json noise_terms_to_json(const an::NoiseTerms& t) {
  json j;
  j["Q"] = term(t.Q, an::q_per_hour, "g*h");
  j["N"] = term(t.N, an::n_per_hour, "g*h^0.5");
  j["B"] = term(t.B);
  j["tau_cp_s"] = num(t.tau_cp_s);
  j["sigma_cp"] = num(t.sigma_cp);
  j["K"] = term(t.K, an::k_per_hour, "g/h^0.5");
  j["R"] = term(t.R, an::r_per_hour, "g/h");
  j["confidence"] = t.confidence;  // of every lo/hi and upper limit here
  // R's reading from the record's drift (noise_terms.hpp DriftReading), SI units; absent when R
  // is the Allan model's (no record behind the points).
  if (t.drift)
    j["drift"] = {{"slope_g_per_s", t.drift->slope}, {"sd_g_per_s", t.drift->sd},
                  {"edf", std::isfinite(t.drift->edf) ? json(t.drift->edf) : json(nullptr)},
                  {"quantile", t.drift->quantile}};
  // The paper's method: log10 sigma = sum_k poly[k] (log10 tau)^k, split at its inflections.
  json paper{{"ok", t.paper.ok}, {"degree", t.paper.degree}, {"poly", t.paper.coef},
             {"inflection_tau_s", t.paper.inflection_tau_s}, {"segments", json::array()}};
  if (!t.paper.reason.empty()) paper["reason"] = t.paper.reason;
  for (const auto& s : t.paper.segments)
    paper["segments"].push_back({{"tau_from_s", s.tau_lo_s}, {"tau_to_s", s.tau_hi_s}, {"slope", s.slope},
                                 {"tau_mid_s", s.tau_mid_s}, {"sigma_mid", s.sigma_mid}, {"term", s.term},
                                 {"term_value", s.term_value}});
  j["paper_fit"] = paper;
  // How the rig's B was read (noise_terms.hpp b_method) and both B values side by side: the
  // paper method's (B) and the least-squares model's (B_lsq); a profile says which one the
  // passport's in_run_b_allan limit applies to ([analysis] b_allan, docs/profiles.md).
  j["b_method"] = t.b_method;
  j["flat_tau_from_s"] = num(t.flat_tau_from_s);
  j["flat_tau_to_s"] = num(t.flat_tau_to_s);
  j["b_edf"] = num(t.b_edf);
  j["B_paper"] = term(t.B);
  j["B_lsq"] = term(t.wls.B);
  // The one model (noise_model.hpp): which terms the data support, the octave points it fitted
  // with the model's EDF, its AICc, and every term's upper limit. A term is reported when AICc
  // selects it or the widest non-negative model's interval excludes 0; the values are those terms'
  // model, fitted together.
  {
    json m{{"ok", t.model.ok},
           {"method", "GLS on ln OADEV^2 at octave taus, model EDF and covariance; terms reported where AICc selects "
                      "them or the widest non-negative model's interval excludes 0, their values fitted together"},
           {"aicc", t.model.aicc}, {"chi2_per_dof", t.model.chi2_per_dof}, {"gof_p", t.model.gof_p},
           {"dropped_short", t.model.dropped_short}, {"long_tau_misfit", t.model.long_tau_misfit},
           {"model_error", t.model.model_error},
           {"tau_s", t.model.tau_s}, {"avar", t.model.avar}, {"edf", t.model.edf}};
    if (!t.model.reason.empty()) m["reason"] = t.model.reason;
    const char* names[5] = {"Q", "N", "B", "K", "R"};
    for (std::size_t k = 0; k < 5; ++k)
      m["terms"][names[k]] = {{"in_model", t.model.in_model[k]}, {"value", t.model.in_model[k] ? json(t.model.value[k]) : json(nullptr)},
                              {"lo", t.model.lo[k]}, {"hi", t.model.hi[k]}, {"upper", t.model.upper[k]},
                              {"share", t.model.share[k]}, {"z", t.model.z[k]}};
    j["model_fit"] = m;
  }
  // The weighted least-squares fit of all five terms: plain values (tau in s) for
  // plotting, the full terms with bounds under "terms".
  json w{{"ok", t.wls.ok}, {"points", t.wls.points}, {"chi2_per_dof", t.wls.chi2_per_dof},
         {"model_error", t.wls.model_error}};
  if (!t.wls.reason.empty()) w["reason"] = t.wls.reason;
  const std::pair<const char*, const an::Term*> wt[] = {
      {"Q", &t.wls.Q}, {"N", &t.wls.N}, {"B", &t.wls.B}, {"K", &t.wls.K}, {"R", &t.wls.R}};
  const std::pair<double (*)(double), const char*> to_hours[] = {
      {an::q_per_hour, "g*h"}, {an::n_per_hour, "g*h^0.5"}, {nullptr, ""}, {an::k_per_hour, "g/h^0.5"}, {an::r_per_hour, "g/h"}};
  for (std::size_t i = 0; i < 5; ++i) {
    const auto& [name, tt] = wt[i];
    w[name] = num(tt->value);
    w["terms"][name] = term(*tt, to_hours[i].first, to_hours[i].second);
    w["terms"][name]["share"] = t.wls.share[i];  // largest share of the model sigma^2 over the taus
    w["terms"][name]["z"] = t.wls.z[i];          // fitted coefficient over its standard error
  }
  j["lsq_fit"] = w;
  // The fitted curves on the Allan taus (noise_terms.hpp's relations), for plots to draw as
  // they are; a term without a value has null.
  const auto curve = [](const std::vector<double>& v) { return v.empty() ? json(nullptr) : json(v); };
  j["curves"] = {{"tau_s", t.curves.tau_s}, {"Q", curve(t.curves.Q)},          {"N", curve(t.curves.N)},
                 {"B", curve(t.curves.B)},  {"K", curve(t.curves.K)},          {"R", curve(t.curves.R)},
                 {"lsq_fit", curve(t.curves.lsq_fit)}, {"paper_poly", curve(t.curves.paper_poly)}};
  return j;
}

nlohmann::json psd_to_json(const analysis::Psd& psd, const std::vector<analysis::Peak>& peaks) {
  nlohmann::json pk = nlohmann::json::array();
  for (const auto& p : peaks) pk.push_back({{"f_hz", p.f_hz}, {"psd", p.psd}, {"prominence_db", p.prominence_db}});
  return {{"f_hz", psd.f_hz}, {"psd", psd.psd}, {"unit", "g^2/Hz"}, {"peaks", pk}};
}

json envelope_to_json(const Envelope& x, const Envelope& y, const std::string& note) {
  auto channel = [](const Envelope& e) { return json{{"mean", e.mean}, {"min", e.min}, {"max", e.max}}; };
  return {{"block_s", x.block_s}, {"t_s", x.t_s}, {"x", channel(x)}, {"y", channel(y)}, {"note", note}};
}

}  // namespace rig::analysis
