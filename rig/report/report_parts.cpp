#include "rig/report/report_parts.hpp"

#include <filesystem>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "rig/core/number_text.hpp"
#include "rig/report/bounded.hpp"
#include "rig/report/json_read.hpp"
#include "rig/report/passport_check.hpp"
#include "rig/report/svg.hpp"
#include "rig/report/svg_plot.hpp"
#include "rig/report/timefmt.hpp"

namespace rig::report {

using nlohmann::json;

namespace {

// Whether two spellings name one folder (a trailing slash, "./", a symlink).
bool same_folder(const std::string& a, const std::string& b) {
  std::error_code ec;
  const bool same = std::filesystem::equivalent(a, b, ec);
  if (!ec) return same;
  return std::filesystem::path(a).lexically_normal() == std::filesystem::path(b).lexically_normal();
}

const char* const kBlue = "#1f77b4";
const char* const kOrange = "#ff7f0e";
const char* const kGreen = "#2ca02c";
const char* const kRed = "#d62728";
const char* const kPurple = "#9467bd";
const char* const kGrey = "#7f7f7f";

// The GOST B values are named by their block length (in_run_b_gost_<N>s: 100 s and 200 s in the
// paper's profile, 2 s and 4 s in ci's); in the contract's order they stand together here.
const char* const kGostB = "in_run_b_gost_<N>s";

// What each passport measurement is (docs/contracts.md, docs/method.md), in the contract's order.
const std::vector<std::pair<std::string, std::string>>& descriptions() {
  static const std::vector<std::pair<std::string, std::string>> d = {
      {"bias", "Bias g_сист, formula (3)"},
      {"base_error", "Base error g_δA, formula (4)"},
      {kGostB, "In-run B, (max − min)/2 of N s averages (GOST)"},
      {"in_run_b_allan", "In-run B from Allan deviation, σ(τ_ср)/0.664"},
      {"tau_cp", "τ_ср, the averaging time in_run_b_allan is read at"},
      {"q", "Quantisation Q"},
      {"n", "Random walk N"},
      {"k", "Rate random walk K"},
      {"r", "Rate ramp R"},
      {"in_run_b_allan_filtered", "In-run B from Allan deviation, filtered output y(t)"},
      {"rms_unfiltered", "RMS error x̂ of x(t)"},
      {"rms_filtered", "RMS error x̂ of y(t)"},
      {"bandwidth_0p5", "Closed-loop bandwidth with the filter, 0.5 level"},
      {"settling_time", "Closed-loop settling time, 1 g step"},
      {"accuracy_class", "Accuracy class from B"},
  };
  return d;
}

std::string badge(const std::string& outcome) {
  std::string cls = "unset";
  if (outcome == "PASS") cls = "pass";
  else if (outcome == "FAIL") cls = "fail";
  else if (outcome == "ABORTED") cls = "aborted";
  else if (outcome == "ERROR") cls = "error";
  return "<span class=\"badge " + cls + "\">" + html_escape(outcome.empty() ? "—" : outcome) + "</span>";
}

std::string figure(const std::string& svg, const std::string& caption) {
  return "<figure>" + svg + "<figcaption>" + caption + "</figcaption></figure>\n";
}

// Seconds between two ISO 8601 times (zones honoured), NaN when either is not one.
double seconds_between(const std::string& a, const std::string& b) {
  const auto ta = history::parse_iso8601(a), tb = history::parse_iso8601(b);
  return ta && tb ? static_cast<double>(*tb - *ta) : kNaN;
}

// The sample rate of the run's records (analysis.json timeseries.rate_hz), NaN when absent.
double record_rate(const json& a) { return number(get(a, {"timeseries", "rate_hz"})); }

std::string duration_text(double s) {
  if (!std::isfinite(s) || s < 0) return "—";
  const long t = std::lround(s);
  char buf[48];
  std::snprintf(buf, sizeof buf, "%ld h %02ld min %02ld s", t / 3600, (t / 60) % 60, t % 60);
  return buf;
}

// A length of time as people say it: "40 s", "30 min", "1 h 05 min".
std::string short_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "—";
  char buf[48];
  if (s < 120) std::snprintf(buf, sizeof buf, "%.3g s", s);
  else if (s < 7200) std::snprintf(buf, sizeof buf, "%.3g min", s / 60);
  else std::snprintf(buf, sizeof buf, "%ld h %02ld min", std::lround(s) / 3600, (std::lround(s) / 60) % 60);
  return buf;
}

// The block length behind each GOST in-run value (in_run_b_gost_*), read from analysis.json's
// in_run.blocks: the block whose length the name states, else the block in the same position
// (the procedure writes the values and the blocks in one order; a profile may set lengths the
// names do not state).
std::map<std::string, double> gost_block_lengths(const json& passport_values, const json& analysis) {
  std::map<std::string, double> out;
  const json* blocks = get(analysis, {"in_run", "blocks"});
  if (!blocks || !blocks->is_array() || !passport_values.is_object()) return out;
  const std::string prefix = "in_run_b_gost_";
  std::size_t k = 0;
  for (const auto& [name, v] : passport_values.items()) {
    if (name.rfind(prefix, 0) != 0) continue;
    double len = kNaN;
    for (const json& b : *blocks)
      if (prefix + fmt_num(number(b, "block_s"), 6) + "s" == name) len = number(b, "block_s");
    if (std::isnan(len) && k < blocks->size()) len = number((*blocks)[k], "block_s");
    ++k;
    if (len > 0) out[name] = len;
  }
  return out;
}

// A term's value, bounds and unit in the passport's per-hour units where the term has them
// (analysis.json carries both; the report converts nothing).
struct Quoted {
  double value = kNaN, lo = kNaN, hi = kNaN;
  std::string unit;
};
Quoted quoted(const json* t) {
  Quoted q;
  if (!t || !t->is_object()) return q;
  const json* ph = get(*t, {"per_hour"});
  const json& src = ph && ph->is_object() ? *ph : *t;
  q.value = number(src, "value");
  q.lo = number(src, "lo");
  q.hi = number(src, "hi");
  q.unit = text(src, "unit");
  return q;
}

// "lo … hi", breakable only after the ellipsis (never inside "7.7e-10").
std::string bounds_text(const std::string& lo, const std::string& hi) {
  return "<span class=\"nw\">" + lo + " …</span> <span class=\"nw\">" + hi + "</span>";
}

// A value and its bounds as the page shows them: rounded to the digits the bounds support
// (bounded.hpp, the GUM's two digits of the half-width) when both bounds are there; else the
// value with `sig` significant digits and the bounds with fmt_num's, as before.
struct ValueCells {
  std::string value, bounds;
};
ValueCells value_cells(double value, double lo, double hi, int sig) {
  if (const auto r = round_to_bounds(value, lo, hi)) return {r->value, bounds_text(r->lo, r->hi)};
  if (!std::isfinite(lo) && !std::isfinite(hi)) return {fmt_num(value, sig), "—"};
  return {fmt_num(value, sig), bounds_text(fmt_num(lo), fmt_num(hi))};
}

// The level of the Allan fit's bounds as a table shows it: "68 %" at one sigma (the default, and
// what an analysis.json without the field had), else the profile's [analysis] confidence.
std::string allan_level(double confidence) {
  if (!(confidence > 0 && confidence < 1) || std::abs(confidence - 0.6826894921370859) < 1e-9) return "68 %";
  return fmt_num(100 * confidence, 3) + " %";
}

// The identified noise terms of one channel: the rig's values (the paper's method for B, the
// least-squares model for the others) with their bounds, and the model's own value of each
// (so both B values stand side by side; B's note says how the paper's B was read).
std::string terms_table(const json& nt, const std::string& ch) {
  const json* lsq = get(nt, {"lsq_fit", "terms"});
  std::ostringstream os;
  os << "<table class=\"terms\" id=\"terms-" << html_escape(ch) << "\"><thead><tr><th>Term (" << html_escape(ch)
     << ")</th><th>Value</th><th>Unit</th><th>Bounds (lo … hi), " << allan_level(number(nt, "confidence"))
     << "</th><th>Least-squares model (GLS)</th>"
        "<th>Note</th></tr></thead><tbody>\n";
  const char* names[][2] = {{"Q", "quantisation"}, {"N", "random walk"}, {"B", "bias instability"},
                            {"K", "rate random walk"}, {"R", "rate ramp"}};
  for (const auto& [term, label] : names) {
    const json* t = get(nt, {term});
    if (!t) continue;
    const Quoted q = quoted(t), fit = quoted(lsq ? get(*lsq, {term}) : nullptr);
    const ValueCells cells = value_cells(q.value, q.lo, q.hi, 4);
    os << "<tr><td>" << term << " — " << label << "</td><td class=\"num\">" << cells.value << "</td><td>"
       << html_escape(q.unit) << "</td><td class=\"num\">" << cells.bounds << "</td><td class=\"num\">"
       << fmt_num(fit.value, 4) << (std::isfinite(fit.value) && fit.unit != q.unit ? " " + html_escape(fit.unit) : "")
       << "</td><td>" << html_escape(text(*t, "reason")) << "</td></tr>\n";
  }
  // tau_cp is where B was read: a flat segment's middle, or the polynomial's minimum (b_method).
  const std::string how = text(nt, "b_method") == "flat_segment" ? "middle of the flat segment"
                          : text(nt, "b_method") == "polynomial_minimum" ? "minimum of the paper's polynomial"
                                                                         : "where B was read";
  os << "<tr><td>τ_ср — " << how << "</td><td class=\"num\">" << fmt_num(number(nt, "tau_cp_s"), 4)
     << "</td><td>s</td><td></td><td></td><td>" << html_escape(text(nt, "b_method")) << "</td></tr>\n</tbody></table>\n";
  return os.str();
}

// The confidence level of a measurement's bounds: the passport's own "confidence" when it
// carries one, else the level of the method that produced the bounds (docs/method.md): GOST R
// 8.736's Student interval at 95 % for the U10/U20 statistics, one standard deviation of the
// weighted Allan fit (68 %) for the noise terms.
std::string interval_level(const std::string& name, const json& v, double allan_confidence) {
  if (const double c = number(v, "confidence"); c > 0 && c < 1) return fmt_num(100 * c, 3) + " %";
  if (name == "bias" || name == "base_error") return "95 %, GOST R 8.736";
  if (name == "q" || name == "n" || name == "k" || name == "r" || name.rfind("in_run_b_allan", 0) == 0) {
    const std::string level = allan_level(allan_confidence);  // the profile's confidence
    // R is read from the record's drift (its reason says so: analysis/noise_terms.cpp), its
    // interval Student's t at the same confidence: not the Allan fit's (a newcomer's review).
    if (name == "r" && text(v, "reason").find("drift of the record") != std::string::npos)
      return level == "68 %" ? "68 %, ±1 σ of the record's drift (Student's t)"
                             : level + " of the record's drift (Student's t)";
    // The paper's B (a flat segment or the polynomial's minimum) is one Allan point over 0.664:
    // its interval is that point's chi-square interval at its EDF, the lower end moved to the
    // noise model's where other terms add to the point (analysis/noise_terms.cpp). Not the fit's
    // one sigma (a metrologist's review).
    const std::string why = text(v, "reason");
    if (name.rfind("in_run_b_allan", 0) == 0 &&
        (why.find("paper: ") != std::string::npos || why.find("paper polynomial") != std::string::npos))
      return why.find("bounds B from above") != std::string::npos
                 ? level + ": χ² upper end of σ(τ_ср)/0.664, lower end the noise model's B"
                 : level + ", χ² interval of σ(τ_ср)/0.664 at its EDF";
    return level == "68 %" ? "68 %, ±1 σ of the Allan fit" : level + " of the Allan fit";
  }
  if (name == "bandwidth_0p5" || name == "settling_time") return "95 %, Student over the loop test's steps";
  return "level not stated";
}

const char* kCss = R"CSS(
:root { --ink:#1b1f24; --mute:#5b6470; --line:#d0d5db; --pass:#1e7b34; --fail:#b3261e; --abort:#a15c00; }
* { box-sizing: border-box; }
body { font: 14px/1.45 "DejaVu Sans", "Liberation Sans", Arial, sans-serif; color: var(--ink); margin: 0; background: #f4f5f7; }
main { max-width: 1000px; margin: 0 auto; padding: 24px 28px 48px; background: #fff; }
h1 { font-size: 22px; margin: 0 0 2px; }
h2 { font-size: 17px; margin: 28px 0 8px; padding-bottom: 3px; border-bottom: 2px solid var(--ink); }
.sub { color: var(--mute); margin: 0 0 16px; }
.ident { display: grid; grid-template-columns: 1fr auto; gap: 16px; align-items: start; }
dl { display: grid; grid-template-columns: max-content 1fr; gap: 3px 14px; margin: 0; }
dt { color: var(--mute); } dd { margin: 0; font-weight: 600; white-space: nowrap; }
dd.wrap { white-space: normal; overflow-wrap: anywhere; }
.verdict { text-align: center; }
.verdict .badge { font-size: 26px; padding: 10px 22px; }
.badge { display: inline-block; padding: 1px 8px; border-radius: 4px; font-weight: 700; color: #fff; background: var(--mute); }
.badge.pass { background: var(--pass); } .badge.fail { background: var(--fail); }
.badge.aborted, .badge.error { background: var(--abort); } .badge.unset { background: #8a939e; }
table { border-collapse: collapse; width: 100%; font-size: 13px; }
th, td { border-bottom: 1px solid var(--line); padding: 4px 6px; text-align: left; vertical-align: top; }
th { background: #eef0f3; font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.name code { font-size: 12px; } td.name div { color: var(--mute); font-size: 12px; }
tr.fail td { background: #fdecea; }
table.terms { margin: 0 0 14px; font-size: 12.5px; }
.notice { border-left: 4px solid var(--abort); background: #fff6e5; padding: 8px 12px; margin: 12px 0; }
.notice ul { margin: 4px 0 0; padding-left: 20px; }
.figs { display: grid; grid-template-columns: 1fr; gap: 10px; }
figure { margin: 8px 0; break-inside: avoid; page-break-inside: avoid; }
figcaption { color: var(--mute); font-size: 12.5px; margin-top: 2px; }
td .lvl { color: var(--mute); font-size: 11px; }
td.time, .nw { white-space: nowrap; }
/* Fixed column widths: the auto layout gives the unbreakable names and numbers so much that the
   reasons wrap every two words; "lo … hi" may break after the ellipsis. */
#passport { table-layout: fixed; }
#passport th:nth-child(1) { width: 20%; } #passport th:nth-child(2) { width: 11%; }
#passport th:nth-child(3) { width: 8%; } #passport th:nth-child(4) { width: 17%; }
#passport th:nth-child(5) { width: 12%; } #passport th:nth-child(6) { width: 9%; }
#passport td.name, #passport td:last-child { overflow-wrap: anywhere; } td.num.bounds { white-space: normal; }
.sign { margin: 18px 0 0; break-inside: avoid; page-break-inside: avoid; }
.sign table { width: 100%; } .sign td, .sign tbody th { height: 34px; border-bottom: 1px solid var(--ink); }
.sign tbody th { width: 16%; background: none; vertical-align: bottom; }
.sign thead th:nth-child(2) { width: 34%; } .sign thead th:nth-child(3) { width: 30%; }
footer { margin-top: 28px; color: var(--mute); font-size: 12px; border-top: 1px solid var(--line); padding-top: 8px; }
@page { size: A4 portrait; margin: 14mm 12mm 16mm; }
@media print {
  body { background: #fff; font-size: 10.5pt; -webkit-print-color-adjust: exact; print-color-adjust: exact; }
  main { max-width: none; padding: 0; }
  h2 { break-after: avoid; page-break-after: avoid; }
  h2.newpage { break-before: page; page-break-before: always; }
  tr, .notice, dl { break-inside: avoid; page-break-inside: avoid; }
  thead { display: table-header-group; }
  figure { margin: 4mm 0; }
  svg.plot { width: 100%; max-height: 118mm; }
  .ident dl { grid-template-columns: max-content auto max-content auto; gap: 2px 12px; }
  table { font-size: 8.5pt; } table.terms { font-size: 8.5pt; }
  td.name div { font-size: 8pt; } td.name code { font-size: 8pt; }
}
)CSS";

}  // namespace

Page::Page(const json& passport, const json& analysis, std::string analysis_problem, std::string run_dir,
           std::vector<std::string> set_aside)
    : p_(passport),
      a_(analysis),
      analysis_problem_(std::move(analysis_problem)),
      set_aside_(std::move(set_aside)) {
  // The folder the page names: the passport's out_dir, unless the page was made from another
  // folder (a colleague's copy), which is then named, with out_dir as where the run wrote it.
  const std::string written = text(p_, "out_dir");
  if (run_dir.empty() || same_folder(run_dir, written)) {
    folder_ = written;
  } else {
    folder_ = std::move(run_dir);
    written_at_ = written;
  }
}

std::string Page::html() {
  const std::string figs = figures();  // first: fills missing_
  std::ostringstream os;
  os << "<!DOCTYPE html>\n<html lang=\"en\">\n" << head() << "<body>\n<main>\n"
     << identity() << notices() << passport_table() << skipped_steps() << signatures() << phases() << figs << captures();
  // The folder read, not the passport's out_dir: the footer says which files this page was made
  // of (a review).
  const std::string& dir = folder_;
  os << "<footer>Generated by " << html_escape("rig " RIG_VERSION) << " from passport.json"
     << (a_.is_object() ? " and analysis.json" : "") << (dir.empty() ? "" : " in " + html_escape(dir))
     << ". Method: docs/method.md (U10/U20, GOST R 8.736-2011, IEEE Std 952/1554).</footer>\n";
  os << "</main>\n</body>\n</html>\n";
  return os.str();
}

std::string Page::head() const {
  const std::string title = "Passport " + text(p_, "serial") + " — " + text(p_, "outcome");
  return "<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
         "<title>" + html_escape(title) + "</title>\n<style>" + kCss + svg_css() + "</style>\n</head>\n";
}

std::string Page::identity() const {
  std::ostringstream os;
  os << "<h1>Acceptance test passport</h1>\n<p class=\"sub\">Quartz pendulum accelerometer with digital feedback "
        "amplifier &middot; U10/U20 method</p>\n";
  os << "<section class=\"ident\"><dl>\n";
  auto row = [&](const char* label, const std::string& value, bool wrap = false) {
    os << "<dt>" << label << "</dt><dd" << (wrap ? " class=\"wrap\"" : "") << ">"
       << html_escape(value.empty() ? "—" : value) << "</dd>\n";
  };
  row("Serial number", text(p_, "serial"));
  // The DUT as it reported itself at bring-up (analysis.json dut).
  const json* dut = get(a_, {"dut"});
  row("DUT firmware", dut ? text(*dut, "firmware") : "");
  const double temp = dut ? number(*dut, "temperature_c") : kNaN;
  char deg[32];
  std::snprintf(deg, sizeof deg, "%.1f", temp);
  row("DUT temperature", std::isfinite(temp) ? std::string(deg) + " °C (at bring-up)" : "");
  row("Profile", text(p_, "profile"));
  // The limits judged by, as `sha256sum profile.toml` in the run folder prints them.
  if (!text(p_, "profile_sha256").empty()) row("Profile SHA-256", text(p_, "profile_sha256"), true);
  row("Plant", text(p_, "plant"));
  if (!text(p_, "station").empty()) row("Station", text(p_, "station"));
  row("Software", text(p_, "software"));
  row("Started", text(p_, "started"));
  row("Finished", text(p_, "finished"));
  // Wall time and device time differ on the emulated plant (it runs faster than real time);
  // device time is the rig clock at the end of the analysis, counted from this session's start.
  row("Wall time", duration_text(seconds_between(text(p_, "started"), text(p_, "finished"))));
  row("Device time", duration_text(number(get(a_, {"device_time_s"}))));
  row("Run folder", folder_, true);
  if (!written_at_.empty()) row("Written at", written_at_, true);
  if (const json* ac = get(p_, {"values", "accuracy_class"}); ac && std::isfinite(number(*ac, "value")))
    row("Accuracy class", text(*ac, "reason") + " (" + fmt_num(number(*ac, "value"), 3) + ")");
  if (!text(p_, "aborted_reason").empty())
    // The reason as recorded, under one label: it often starts with its kind ("aborted: e-stop
    // line opened"), which read "Aborted because aborted: ..." (a review).
    row("Why it ended", text(p_, "aborted_reason"), true);
  os << "</dl>\n<div class=\"verdict\">" << badge(text(p_, "outcome")) << "</div></section>\n";
  return os.str();
}

std::string Page::notices() const {
  std::vector<std::string> items;
  if (!p_.contains("schema")) items.push_back("passport.json has no \"schema\" field; read as rig.passport/1");
  if (!analysis_problem_.empty()) items.push_back(analysis_problem_ + "; the plots that need it are left out");
  for (const std::string& m : missing_) items.push_back(m);
  if (items.empty()) return "";
  std::ostringstream os;
  os << "<div class=\"notice\" id=\"missing\"><strong>Incomplete data.</strong> This report shows what the run "
        "folder holds; missing:<ul>\n";
  for (const std::string& i : items) os << "<li>" << html_escape(i) << "</li>\n";
  os << "</ul></div>\n";
  return os.str();
}

std::string Page::passport_table() const {
  std::ostringstream os;
  os << "<h2>Measurements</h2>\n";
  const json* values = get(p_, {"values"});
  if (!values || !values->is_object() || values->empty()) {
    os << "<p class=\"notice\">The passport holds no measurements.</p>\n";
    return os.str();
  }
  os << "<table id=\"passport\"><thead><tr><th>Measurement</th><th>Value</th><th>Unit</th><th>Bounds (lo … hi), "
        "interval level</th><th>Limits</th><th>Outcome</th><th>Reason</th></tr></thead><tbody>\n";
  const std::map<std::string, double> gost = gost_block_lengths(*values, a_);
  // What a row is: the passport's own description when it has one, then the report's; a GOST
  // in-run row names the block length its value was computed from.
  auto describe = [&](const std::string& name, const std::string& fallback) {
    if (auto g = gost.find(name); g != gost.end())
      return "In-run B, (max − min)/2 of " + fmt_num(g->second, 4) + " s block means (GOST)";
    if (const json* b = get(a_, {"in_run", "blocks"}); name == "accuracy_class" && b && b->is_array() && !b->empty())
      return "Accuracy class from B of the " + fmt_num(number((*b)[0], "block_s"), 4) + " s blocks (GOST)";
    const std::string own = text(get(*values, {name.c_str(), "description"}));
    return own.empty() ? fallback : own;
  };
  // The contract's measurements first, in its order, then any others the procedure added.
  std::vector<std::pair<std::string, std::string>> order;
  for (const auto& [name, desc] : descriptions()) {
    if (name == kGostB) {  // each block length the passport has, in its order
      for (const auto& item : values->items())
        if (is_gost_b(item.key()))
          order.emplace_back(item.key(), "In-run B, (max − min)/2 of " +
                                             item.key().substr(14, item.key().size() - 15) + " s averages (GOST)");
    } else if (values->contains(name)) {
      order.emplace_back(name, desc);
    }
  }
  for (const auto& item : values->items()) {
    const std::string& name = item.key();  // not a structured binding: clang 14 cannot capture one
    const bool known = is_gost_b(name) || std::any_of(descriptions().begin(), descriptions().end(),
                                                      [&](const auto& d) { return d.first == name; });
    if (!known) order.emplace_back(name, "");
  }
  for (const auto& [name, fallback] : order) {
    const std::string desc = describe(name, fallback);
    const json& v = (*values)[name];
    const std::string outcome = text(v, "outcome");
    os << "<tr" << (outcome == "FAIL" ? " class=\"fail\"" : "") << "><td class=\"name\"><code>" << html_escape(name)
       << "</code>" << (desc.empty() ? "" : "<div>" + html_escape(desc) + "</div>") << "</td>";
    const json* val = get(v, {"value"});
    const double lo = number(v, "lo"), hi = number(v, "hi");
    ValueCells cells = value_cells(number(val), lo, hi, 5);
    const json* lim = get(v, {"limits"});
    const bool limited = lim && lim->is_array() && lim->size() == 2;
    std::string limits = "—";
    if (limited) {
      const double a = number(&(*lim)[0]), b = number(&(*lim)[1]);
      limits = "[" + (std::isfinite(a) ? fmt_num(a) : "−∞") + ", " + (std::isfinite(b) ? fmt_num(b) : "+∞") + "]";
      // A failed value with the digits that put it outside its limits, not those its bounds
      // support (the page read 0.00314 against [0, 0.00314]: a review), as the console and JUnit.
      // Any other value too where its rounding and the limits' put it on the wrong side (a PASS
      // read 0.0024224 beside [0, 0.002422]: a metrologist's review).
      if (val && val->is_number() && std::isfinite(a) && std::isfinite(b) &&
          (outcome == "FAIL" || !shown_in_order({cells.value, fmt_num(a), fmt_num(b)}, val->get<double>(), a, b))) {
        const ShownOutside so = shown_against_limits(val->get<double>(), a, b, 5);
        cells.value = html_escape(so.value);
        limits = "[" + so.lo + ", " + so.hi + "]";
      }
    }
    os << "<td class=\"num\">" << (val && val->is_number() ? cells.value : html_escape(text(val).empty() ? "—" : text(val)))
       << "</td><td>" << html_escape(text(v, "unit")) << "</td>";
    os << "<td class=\"num bounds\">" << cells.bounds;
    if (std::isfinite(lo) || std::isfinite(hi))
      os << "<div class=\"lvl\">" << html_escape(interval_level(name, v, number(get(a_, {"allan", "confidence"}))))
         << "</div>";
    os << "</td>";
    os << "<td class=\"num\">" << html_escape(limits) << "</td><td>" << badge(outcome) << "</td><td>"
       << html_escape(text(v, "reason")) << "</td></tr>\n";
  }
  os << "</tbody></table>\n";
  return os.str();
}

// The procedure steps the DUT could not take (passport.json `skipped`, written only when there
// are any, e.g. [dut] commands = false: identify, set the output filter, the loop test) and
// why, beside the measurements whose null values they explain. No section without any.
std::string Page::skipped_steps() const {
  const json* sk = get(p_, {"skipped"});
  if (!sk || !sk->is_array() || sk->empty()) return "";
  std::ostringstream os;
  os << "<h2>Skipped steps</h2>\n<table id=\"skipped\"><thead><tr><th>Step</th><th>Reason</th></tr></thead><tbody>\n";
  for (const json& x : *sk)
    os << "<tr><td>" << html_escape(text(x, "step").empty() ? text(&x) : text(x, "step")) << "</td><td>"
       << html_escape(text(x, "reason")) << "</td></tr>\n";
  os << "</tbody></table>\n";
  return os.str();
}

// The sign-off of a paper passport: who tested, who checked, when; blank lines to sign by hand.
std::string Page::signatures() const {
  std::ostringstream os;
  os << "<section class=\"sign\" id=\"signatures\"><table><thead><tr><th></th><th>Name</th><th>Signature</th>"
        "<th>Date</th></tr></thead><tbody>\n";
  for (const char* role : {"Tested by", "Checked by"})
    os << "<tr><th scope=\"row\">" << role << "</th><td></td><td></td><td></td></tr>\n";
  os << "</tbody></table></section>\n";
  return os.str();
}

std::string Page::phases() const {
  const json* ph = get(p_, {"phases"});
  if (!ph || !ph->is_array() || ph->empty()) return "";
  std::ostringstream os;
  os << "<h2>Phases</h2>\n<table id=\"phases\"><thead><tr><th>#</th><th>Phase</th><th>Status</th><th>Started</th>"
        "<th>Finished</th><th>Message</th></tr></thead><tbody>\n";
  int i = 0;
  for (const json& x : *ph) {
    const std::string st = text(x, "status");
    const std::string cls = st == "done" ? "PASS" : st == "failed" ? "FAIL" : st == "aborted" ? "ABORTED" : "";
    os << "<tr><td>" << ++i << "</td><td>" << html_escape(text(x, "title").empty() ? text(x, "id") : text(x, "title"))
       << "</td><td>" << (cls.empty() ? html_escape(st) : "<span class=\"badge " +
                                                             std::string(cls == "PASS" ? "pass" : cls == "FAIL" ? "fail" : "aborted") +
                                                             "\">" + html_escape(st) + "</span>")
       << "</td><td class=\"time\">" << html_escape(text(x, "started")) << "</td><td class=\"time\">"
       << html_escape(text(x, "finished"))
       << "</td><td>" << html_escape(text(x, "message")) << "</td></tr>\n";
  }
  os << "</tbody></table>\n";
  return os.str();
}

std::string Page::captures() const {
  const json* c = get(p_, {"captures"});
  const bool recorded = c && c->is_array() && !c->empty();
  if (!recorded && set_aside_.empty()) return "";
  std::ostringstream os;
  os << "<h2>Captures</h2>\n";
  if (recorded) {
    os << "<p>Raw recordings in the run folder (rig capture format; <code>rig analyze FILE "
          "--input capture</code> re-analyses one):</p><ul id=\"captures\">\n";
    for (const json& x : *c) os << "<li><code>" << html_escape(text(&x)) << "</code></li>\n";
    os << "</ul>\n";
  }
  if (!set_aside_.empty()) {
    os << "<p>Set aside: what an interrupted attempt left (a recording the rig retried after a fault in it, or one "
          "a resume repeated), kept as it was and never read; nothing in this passport comes from them:</p>"
          "<ul id=\"set-aside\">\n";
    for (const std::string& f : set_aside_) os << "<li><code>" << html_escape(f) << "</code></li>\n";
    os << "</ul>\n";
  }
  return os.str();
}

std::string Page::figures() {
  std::ostringstream os;
  os << "<h2 class=\"newpage\">Allan deviation</h2>\n<div class=\"figs\">" << allan("x") << allan("y") << "</div>\n";
  os << "<h2 class=\"newpage\">Spectra and output</h2>\n<div class=\"figs\">" << psd("x") << psd("y") << timeseries()
     << "</div>\n";
  os << "<h2 class=\"newpage\">Zero signal: U10/U20 averages and in-run stability</h2>\n<div class=\"figs\">"
     << averages() << in_run() << "</div>\n";
  os << "<h2 class=\"newpage\">Closed loop with the output filter</h2>\n<div class=\"figs\">" << step() << freq()
     << "</div>\n";
  return os.str();
}

std::string Page::allan(const std::string& ch) {
  const std::string what = ch == "x" ? "raw output x(t)" : "filtered output y(t)";
  const json* al = get(a_, {"allan", ch.c_str()});
  const json* od = al ? get(*al, {"oadev"}) : nullptr;
  if (!od || !od->is_array() || od->empty()) {
    if (a_.is_object()) missing_.push_back("Allan deviation of the " + what + " (analysis.json allan." + ch + ")");
    return "";
  }
  const json* nt = get(*al, {"noise_terms"});
  if (nt && !get(*nt, {"curves"}))
    missing_.push_back("the fitted noise-term curves of " + ch + " (analysis.json allan." + ch + ".noise_terms.curves)");
  const double confidence = number(get(a_, {"allan", "confidence"}));
  const Plot p = allan_plot(*od, nt, confidence, "allan-" + ch, "Overlapping Allan deviation, " + what,
                            ch == "x" ? kBlue : kGreen);
  const std::string level = std::isfinite(confidence) ? fmt_num(100 * confidence, 3) + " % " : "";
  std::string caption = "Allan deviation of the " + html_escape(what) + " with " + level + "confidence bounds (τ in s).";
  if (nt) {
    caption += " Dashed: each identified noise term alone (Q −1, N −½, B 0, K +½, R +1), its value in the "
               "passport's per-hour units.";
    if (const json* r = get(*nt, {"R"}); r && !text(*r, "reason").empty())
      caption += " R: " + html_escape(text(*r, "reason")) + ".";
  }
  return figure(to_svg(p), caption + " B = σ(τ_ср)/0.664 (docs/method.md, IEEE Std 952 Annex C).") +
         (nt ? terms_table(*nt, ch) : "");
}

std::string Page::psd(const std::string& ch) {
  const std::string what = ch == "x" ? "raw output x(t)" : "filtered output y(t)";
  const json* ps = get(a_, {"psd", ch.c_str()});
  if (!ps || !get(*ps, {"f_hz"})) {
    if (a_.is_object()) missing_.push_back("power spectral density of the " + what + " (analysis.json psd." + ch + ")");
    return "";
  }
  const double rate = record_rate(a_);  // the PSD's sampling rate: the records' (welch at the procedure's rate)
  const Plot p = psd_plot(*ps, "psd-" + ch, "Power spectral density, " + what, ch == "x" ? kBlue : kGreen, rate);
  std::vector<bool> labelled;
  const std::string svg = to_svg(p, &labelled);
  // The caption names exactly the peaks the plot labels.
  const std::string peaks = labelled_peaks(p, labelled);
  const auto unlabelled = std::count(labelled.begin(), labelled.end(), false);
  std::string caption = "PSD (Welch) of the " + html_escape(what) + "; " +
                        (peaks.empty() ? std::string("no peak labelled") : "labelled peaks: " + html_escape(peaks)) + ".";
  if (unlabelled > 0)
    caption += " " + std::to_string(unlabelled) + " further detected peak" + (unlabelled > 1 ? "s are" : " is") +
               " circled without a label (no room).";
  if (!peaks.empty() && !alias_note(rate).empty()) caption += " " + html_escape(alias_note(rate));
  return "<figure>" + svg + "<figcaption data-peaks=\"" + html_escape(peaks) + "\">" + caption +
         "</figcaption></figure>\n";
}

// The output over the whole raw capture, from analysis.json's block envelope, as two plots:
// the block means alone on their own scale (the zero drift, micro-g), then each block's raw
// minimum and maximum with the means (the spread, dominated by vibration and quantisation,
// milli-g). One plot for both would flatten the means into a line.
std::string Page::timeseries() {
  const json* env = get(a_, {"output_envelope"});
  const std::vector<double> t = env ? numbers(get(*env, {"t_s"})) : std::vector<double>{};
  if (t.empty()) {
    if (a_.is_object()) missing_.push_back("the output over the raw capture (analysis.json output_envelope)");
    return "";
  }
  const double block = number(*env, "block_s");
  const std::string blocks = fmt_num(block, 3) + " s block means";
  struct Channel {
    const char* key;
    const char* what;
    const char* band;
    const char* line;
    double width;
  };
  // y under x: the filtered output's mean is drawn wider so that x stays visible on it.
  const Channel chans[] = {{"y", "y(t), filtered", "#fdd0a2", "#e6550d", 2.2}, {"x", "x(t), no filter", "#9ecae1", "#08519c", 1.0}};
  Plot means, range;
  means.id = "timeseries";
  means.title = "Output over the raw capture: " + blocks;
  range.id = "timeseries-range";
  range.title = "Output over the raw capture: raw minimum and maximum of each block";
  means.x_label = range.x_label = "t, s";
  means.y_label = "block mean, g";
  range.y_label = "output, g";
  for (const Channel& c : chans) {
    const json* ch = get(*env, {c.key});
    if (!ch) continue;
    range.series.push_back({std::string(c.what) + ": min … max", t, numbers(get(*ch, {"mean"})),
                            numbers(get(*ch, {"min"})), numbers(get(*ch, {"max"})), c.band, Series::Style::band, false,
                            1.0});
  }
  for (const Channel& c : chans) {
    const json* ch = get(*env, {c.key});
    if (!ch) continue;
    const Series s{std::string(c.what) + ": " + blocks, t, numbers(get(*ch, {"mean"})), {}, {}, c.line,
                   Series::Style::line, false, c.width};
    means.series.push_back(s);
    range.series.push_back(s);
  }
  const std::string note = text(*env, "note");
  const std::string what = note.empty() ? std::string(".") : "; " + html_escape(note) + ".";
  return figure(to_svg(means), "Means of " + fmt_num(block, 3) + " s blocks over the whole raw capture (cf. the "
                               "paper's Fig. 5)" + what) +
         figure(to_svg(range), "The minimum and maximum raw sample of each " + fmt_num(block, 3) +
                                   " s block (shaded) around the block means" + what);
}

std::string Page::averages() {
  const json* runs = get(a_, {"runs"});
  if (!runs || !runs->is_array() || runs->empty()) {
    if (a_.is_object()) missing_.push_back("the 100 s averages of the U10/U20 runs (analysis.json runs)");
    return "";
  }
  // Each run's length from its samples, so the title says what this profile averaged.
  const double rate = record_rate(a_), n0 = number((*runs)[0], "n");
  const std::string run_len = rate > 0 && n0 > 0 ? fmt_num(n0 / rate, 4) + " s averages" : "Averages";
  Plot p;
  p.id = "averages";
  p.title = run_len + " of the U10 and U20 runs";
  p.x_label = "run";
  p.y_label = "mean output, g";
  Series u10{"U10 (pendulum down)", {}, {}, {}, {}, kBlue, Series::Style::markers, false, 1.5};
  Series u20{"U20 (pendulum up)", {}, {}, {}, {}, kOrange, Series::Style::markers, false, 1.5};
  for (const json& r : *runs) {
    Series& s = text(r, "orientation") == "U20" ? u20 : u10;
    s.x.push_back(number(r, "index"));
    s.y.push_back(number(r, "mean_g"));
  }
  p.series.push_back(u10);
  p.series.push_back(u20);
  const double bias = number(get(p_, {"values", "bias", "value"}));
  const double base = number(get(p_, {"values", "base_error", "value"}));
  if (std::isfinite(bias)) {
    p.lines.push_back({false, bias, "g_сист = " + fmt_num(bias, 5) + " g", "#333"});
    if (std::isfinite(base)) {
      p.lines.push_back({false, bias + base, "g_сист + g_δA", kGrey});
      p.lines.push_back({false, bias - base, "g_сист − g_δA", kGrey});
    }
  }
  return figure(to_svg(p), "Each point is one run averaged over its duration; bias g_сист = mean of (x10+x20)/2, "
                           "base error g_δA = mean of (x10−x20)/2 (docs/method.md formulas 3, 4).");
}

std::string Page::in_run() {
  const json* blocks = get(a_, {"in_run", "blocks"});
  if (!blocks || !blocks->is_array() || blocks->empty()) {
    if (a_.is_object()) missing_.push_back("the in-run block averages (analysis.json in_run)");
    return "";
  }
  const double rate = record_rate(a_), n = number(get(a_, {"in_run", "n"}));
  Plot p;
  p.id = "in-run";
  p.title = "In-run zero signal, block averages of the " +
            (rate > 0 && n > 0 ? short_duration(n / rate) + " " : std::string()) + "in-run record";
  p.x_label = "time from start, s";
  p.y_label = "block mean, g";
  const char* colors[] = {kBlue, kRed, kGreen, kPurple};
  std::size_t k = 0;
  std::string caption;
  for (const json& b : *blocks) {
    const double bs = number(b, "block_s"), bg = number(b, "b_g");
    const std::vector<double> m = numbers(get(b, {"means_g"}));
    Series s{fmt_num(bs, 4) + " s blocks, B = " + fmt_num(bg, 3) + " g", {}, m, {}, {}, colors[k++ % 4],
             Series::Style::line_markers, false, 1.2};
    for (std::size_t i = 0; i < m.size(); ++i) s.x.push_back((static_cast<double>(i) + 0.5) * bs);
    p.series.push_back(std::move(s));
  }
  return figure(to_svg(p), "B = (max − min)/2 of the block averages (docs/method.md, procedure B).");
}

std::string Page::step() {
  const json* st = get(a_, {"loop", "step"});
  if (!st) {
    if (a_.is_object()) missing_.push_back("the closed-loop step response (analysis.json loop.step)");
    return "";
  }
  Plot p;
  p.id = "step";
  p.title = "Closed-loop response to a 1 g step";
  p.x_label = "t, s";
  p.y_label = "output, g";
  const std::vector<double> t = numbers(get(*st, {"t_s"}));
  p.series.push_back({"x(t), no filter", t, numbers(get(*st, {"x"})), {}, {}, kBlue, Series::Style::line, false, 1.5});
  p.series.push_back({"y(t), with the filter", t, numbers(get(*st, {"y"})), {}, {}, kOrange, Series::Style::line, false, 1.5});
  const double ts = number(get(a_, {"loop", "settling_time_s"}));
  const double band = number(get(a_, {"loop", "settling_band"})), gain = number(get(a_, {"loop", "dc_gain"}));
  std::string scale;
  if (ts > 0) {
    p.lines.push_back({true, ts, "t_рег = " + fmt_num(ts, 3) + " s", kRed});
    // The axis spans three settling times: the transient fills the plot, and the flat tail
    // after it shows the output has stayed in the band.
    p.x_range = std::pair{0.0, 3 * ts};
    scale = " Time axis: three settling times.";
  }
  if (band > 0 && std::isfinite(gain)) {
    p.lines.push_back({false, gain * (1 + band), "+" + fmt_num(100 * band, 3) + " %", kGrey});
    p.lines.push_back({false, gain * (1 - band), "−" + fmt_num(100 * band, 3) + " %", kGrey});
  }
  return figure(to_svg(p), "Step response (cf. the paper's Fig. 6); t_рег: the output stays within ±" +
                               fmt_num(100 * band, 3) + " % of its final value." + scale);
}

std::string Page::freq() {
  const json* fr = get(a_, {"loop", "freq"});
  if (!fr) {
    if (a_.is_object()) missing_.push_back("the closed-loop frequency response (analysis.json loop.freq)");
    return "";
  }
  Plot p;
  p.id = "freq";
  p.title = "Closed-loop amplitude response";
  p.x_label = "f, Hz";
  p.y_label = "|H(f)|";
  p.log_x = true;
  const std::vector<double> f = numbers(get(*fr, {"f_hz"}));
  p.series.push_back({"no filter", f, numbers(get(*fr, {"mag_x"})), {}, {}, kBlue, Series::Style::line, false, 1.5});
  p.series.push_back({"with the filter", f, numbers(get(*fr, {"mag_y"})), {}, {}, kOrange, Series::Style::line, false, 1.5});
  p.lines.push_back({false, 0.5, "0.5 level", kGrey});
  const double bw = number(get(a_, {"loop", "bandwidth_0p5_hz"}));
  if (bw > 0) p.lines.push_back({true, bw, "f_пп = " + fmt_num(bw, 4) + " Hz", kRed});
  return figure(to_svg(p), "Amplitude response; bandwidth read at the 0.5 level (cf. the paper's Fig. 7).");
}

}  // namespace rig::report
