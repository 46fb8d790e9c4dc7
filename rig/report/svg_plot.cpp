#include "rig/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>

#include "rig/report/json_read.hpp"

namespace rig::report {

using nlohmann::json;

namespace {

std::vector<double> field(const json& arr, const char* key) {
  std::vector<double> out;
  if (!arr.is_array()) return out;
  for (const json& o : arr) out.push_back(number(o, key));
  return out;
}

// A term's value and unit as the passport quotes it: per hour where the term has it.
std::string term_label(const json& t, const char* name) {
  const json* ph = get(t, {"per_hour"});
  const json& src = ph && ph->is_object() ? *ph : t;
  return std::string(name) + " = " + fmt_num(number(src, "value"), 3) + " " + text(src, "unit");
}

}  // namespace

Plot allan_plot(const json& oadev, const json* nt, double confidence, const std::string& id, const std::string& title,
                const std::string& color) {
  Plot p;
  p.id = id;
  p.title = title;
  p.x_label = "τ, s";
  p.y_label = "σ(τ), g";
  p.log_x = p.log_y = true;
  const std::string level = std::isfinite(confidence) ? fmt_num(100 * confidence, 3) + " % bounds" : "bounds";
  p.series.push_back({"OADEV with " + level, field(oadev, "tau_s"), field(oadev, "dev"), field(oadev, "lo"),
                      field(oadev, "hi"), color, Series::Style::line_markers, false, 1.5});
  if (!nt || !nt->is_object()) return p;
  const json* curves = get(*nt, {"curves"});
  const std::vector<double> tau = curves ? numbers(get(*curves, {"tau_s"})) : std::vector<double>{};
  // Each identified term alone (noise_terms.hpp's sigma_X), dashed.
  const std::pair<const char*, const char*> terms[] = {
      {"Q", "#9467bd"}, {"N", "#ff7f0e"}, {"B", "#d62728"}, {"K", "#8c564b"}, {"R", "#7f7f7f"}};
  for (const auto& [name, c] : terms) {
    const json* t = get(*nt, {name});
    const std::vector<double> y = curves ? numbers(get(*curves, {name})) : std::vector<double>{};
    if (!t || y.empty() || y.size() != tau.size()) continue;
    p.series.push_back({term_label(*t, name), tau, y, {}, {}, c, Series::Style::line, true, 1.2, false});
  }
  if (curves) {
    if (const std::vector<double> y = numbers(get(*curves, {"lsq_fit"})); !y.empty() && y.size() == tau.size())
      p.series.push_back({"weighted least-squares fit, identified terms together", tau, y, {}, {}, "#222",
                          Series::Style::line, false, 1.0, false});
    if (const std::vector<double> y = numbers(get(*curves, {"paper_poly"})); !y.empty() && y.size() == tau.size())
      p.series.push_back({"4th-degree polynomial (paper)", tau, y, {}, {}, "#17becf", Series::Style::line, false, 1.2,
                          false});
  }
  // The paper's straight segments: slope `a` through the polynomial at the segment's middle.
  if (const json* pf = get(*nt, {"paper_fit"}); pf)
    if (const json* segs = get(*pf, {"segments"}); segs && segs->is_array()) {
      int k = 0;
      for (const json& sg : *segs) {
        const double a = number(sg, "tau_from_s"), b = number(sg, "tau_to_s"), slope = number(sg, "slope"),
                     tm = number(sg, "tau_mid_s"), sm = number(sg, "sigma_mid");
        if (!(a > 0 && b > a && tm > 0 && sm > 0 && std::isfinite(slope))) continue;
        p.series.push_back({k++ == 0 ? "polynomial segments (slope at τ_mid)" : "", {a, b},
                            {sm * std::pow(a / tm, slope), sm * std::pow(b / tm, slope)}, {}, {}, "#e377c2",
                            Series::Style::line, false, 3.0, false});
        p.markers.push_back({tm, sm, "a = " + fmt_num(slope, 2), "#e377c2"});
      }
    }
  const double tau_cp = number(*nt, "tau_cp_s"), sigma_cp = number(*nt, "sigma_cp");
  const json* b = get(*nt, {"B"});
  if (tau_cp > 0) {
    p.lines.push_back({true, tau_cp, "τ_ср = " + fmt_num(tau_cp, 3) + " s", "#d62728"});
    if (sigma_cp > 0 && b) p.markers.push_back({tau_cp, sigma_cp, term_label(*b, "B"), "#d62728", true});
  }
  return p;
}

std::string peak_label(double f_hz, double rate_hz) {
  std::string label = fmt_num(f_hz, 4) + " Hz";
  // Sampling at fs cannot tell f from fs − f (nor from k·fs ± f, whose first is fs − f): both
  // give the same samples. Named, not judged: what lies above Nyquist is unknown to the rig.
  if (rate_hz > 0 && f_hz > 0 && f_hz < rate_hz / 2) label += " or " + fmt_num(rate_hz - f_hz, 4) + " Hz";
  return label;
}

std::string alias_note(double rate_hz) {
  if (!(rate_hz > 0)) return "";
  return "Sampled at " + fmt_num(rate_hz, 6) + " Hz, a line at f and one at " + fmt_num(rate_hz, 6) +
         " Hz − f give the same samples (aliasing): each peak is labelled with both; the record cannot tell which "
         "is real.";
}

Plot psd_plot(const json& psd, const std::string& id, const std::string& title, const std::string& color,
              double rate_hz) {
  Plot p;
  p.id = id;
  p.title = title;
  p.x_label = "f, Hz";
  p.y_label = "PSD, " + (text(psd, "unit").empty() ? std::string("g^2/Hz") : text(psd, "unit"));
  p.log_x = p.log_y = true;
  p.series.push_back({"PSD (Welch)", numbers(get(psd, {"f_hz"})), numbers(get(psd, {"psd"})), {}, {}, color,
                      Series::Style::line, false, 1.0});
  if (const json* pk = get(psd, {"peaks"}); pk && pk->is_array())
    for (const json& k : *pk)
      p.markers.push_back({number(k, "f_hz"), number(k, "psd"), peak_label(number(k, "f_hz"), rate_hz), "#d62728"});
  return p;
}

std::string labelled_peaks(const Plot& p, const std::vector<bool>& labelled) {
  std::vector<const Marker*> placed;  // in ascending frequency, as a reader scans the axis
  for (std::size_t i = 0; i < p.markers.size() && i < labelled.size(); ++i)
    if (labelled[i]) placed.push_back(&p.markers[i]);
  std::stable_sort(placed.begin(), placed.end(), [](const Marker* a, const Marker* b) { return a->x < b->x; });
  std::string out;
  for (const Marker* m : placed) out += (out.empty() ? "" : ", ") + m->text;
  return out;
}

}  // namespace rig::report
