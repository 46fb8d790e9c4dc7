#include "rig/report/report_parts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "rig/report/svg.hpp"
#include "rig/report/timefmt.hpp"

namespace rig::report {

using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kBlue = "#1f77b4";
const char* const kOrange = "#ff7f0e";
const char* const kGreen = "#2ca02c";
const char* const kRed = "#d62728";
const char* const kPurple = "#9467bd";
const char* const kBrown = "#8c564b";
const char* const kGrey = "#7f7f7f";

// Walks a path of keys; nullptr when any step is absent or not an object.
const json* get(const json& j, std::initializer_list<const char*> path) {
  const json* cur = &j;
  for (const char* k : path) {
    if (!cur->is_object()) return nullptr;
    auto it = cur->find(k);
    if (it == cur->end()) return nullptr;
    cur = &*it;
  }
  return cur;
}

double number(const json* j) { return j && j->is_number() ? j->get<double>() : kNaN; }
double number(const json& j, const char* key) { return number(get(j, {key})); }

std::string text(const json* j) {
  if (!j || j->is_null()) return "";
  return j->is_string() ? j->get<std::string>() : j->dump();
}
std::string text(const json& j, const char* key) { return text(get(j, {key})); }

// A JSON array of numbers (null -> NaN); empty when absent.
std::vector<double> numbers(const json* j) {
  std::vector<double> out;
  if (!j || !j->is_array()) return out;
  out.reserve(j->size());
  for (const json& v : *j) out.push_back(v.is_number() ? v.get<double>() : kNaN);
  return out;
}

std::vector<double> field(const json* arr, const char* key) {
  std::vector<double> out;
  if (!arr || !arr->is_array()) return out;
  for (const json& o : *arr) out.push_back(number(o, key));
  return out;
}

// What each passport measurement is (docs/contracts.md, docs/method.md), in the passport's order.
const std::vector<std::pair<std::string, std::string>>& descriptions() {
  static const std::vector<std::pair<std::string, std::string>> d = {
      {"bias", "Bias g_сист, formula (3)"},
      {"base_error", "Base error g_δA, formula (4)"},
      {"in_run_b_gost_100s", "In-run B, (max − min)/2 of 100 s averages (GOST)"},
      {"in_run_b_gost_200s", "In-run B, (max − min)/2 of 200 s averages (GOST)"},
      {"in_run_b_allan", "In-run B from Allan deviation, σ(τ_ср)/0.664"},
      {"tau_cp", "τ_ср, middle of the flat Allan segment"},
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

// Noise-term coefficient in the seconds basis the Allan plot uses (τ in s):
// values quoted per hour (g*h, g*h^0.5, g/h^0.5, g/h) are converted.
double seconds_basis(const std::string& term, double v, const std::string& unit) {
  const bool hours = unit.find('h') != std::string::npos;
  if (!hours || !std::isfinite(v)) return v;
  if (term == "Q") return v * 3600.0;          // g*h -> g*s
  if (term == "N") return v * 60.0;            // g*h^0.5 -> g*s^0.5
  if (term == "K") return v / 60.0;            // g/h^0.5 -> g/s^0.5
  if (term == "R") return v / 3600.0;          // g/h -> g/s
  return v;
}

// Allan deviation of each noise term vs τ (IEEE 952 / 1293; docs/method.md slope relations).
double term_sigma(const std::string& term, double c, double tau) {
  if (term == "Q") return std::sqrt(3.0) * c / tau;
  if (term == "N") return c / std::sqrt(tau);
  if (term == "B") return 0.664 * c;  // sqrt(2 ln2 / π) B
  if (term == "K") return c * std::sqrt(tau / 3.0);
  if (term == "R") return c * tau / std::sqrt(2.0);
  return kNaN;
}

std::vector<double> log_grid(double lo, double hi, int n) {
  std::vector<double> out;
  if (!(lo > 0 && hi > lo)) return out;
  for (int i = 0; i < n; ++i) out.push_back(lo * std::pow(hi / lo, i / double(n - 1)));
  return out;
}

// Seconds between two ISO 8601 times (zones honoured), NaN when either is not one.
double seconds_between(const std::string& a, const std::string& b) {
  const auto ta = history::parse_iso8601(a), tb = history::parse_iso8601(b);
  return ta && tb ? static_cast<double>(*tb - *ta) : kNaN;
}

std::string duration_text(double s) {
  if (!std::isfinite(s) || s < 0) return "—";
  const long t = std::lround(s);
  char buf[48];
  std::snprintf(buf, sizeof buf, "%ld h %02ld min %02ld s", t / 3600, (t / 60) % 60, t % 60);
  return buf;
}

// The identified noise terms of one channel: slope method (with bounds) and the
// least-squares fit of all terms, side by side.
std::string terms_table(const json& nt, const std::string& ch) {
  const json* lsq = get(nt, {"lsq_fit"});
  std::ostringstream os;
  os << "<table class=\"terms\" id=\"terms-" << html_escape(ch) << "\"><thead><tr><th>Term (" << html_escape(ch)
     << ")</th><th>Value</th><th>Unit</th><th>Bounds (lo … hi)</th><th>Least-squares fit</th><th>Note</th></tr>"
        "</thead><tbody>\n";
  const char* names[][2] = {{"Q", "quantisation"}, {"N", "random walk"}, {"B", "bias instability"},
                            {"K", "rate random walk"}, {"R", "rate ramp"}};
  for (const auto& [term, label] : names) {
    const json* t = get(nt, {term});
    if (!t) continue;
    const double lo = number(*t, "lo"), hi = number(*t, "hi"), fit = lsq ? number(*lsq, term) : kNaN;
    os << "<tr><td>" << term << " — " << label << "</td><td class=\"num\">" << fmt_num(number(*t, "value"), 4)
       << "</td><td>" << html_escape(text(*t, "unit")) << "</td><td class=\"num\">"
       << (std::isfinite(lo) || std::isfinite(hi) ? fmt_num(lo) + " … " + fmt_num(hi) : "—") << "</td><td class=\"num\">"
       << fmt_num(fit, 4) << "</td><td>" << html_escape(text(*t, "reason")) << "</td></tr>\n";
  }
  os << "<tr><td>τ_ср — middle of the flat segment</td><td class=\"num\">" << fmt_num(number(nt, "tau_cp_s"), 4)
     << "</td><td>s</td><td></td><td></td><td></td></tr>\n</tbody></table>\n";
  return os.str();
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
dt { color: var(--mute); } dd { margin: 0; font-weight: 600; word-break: break-all; }
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
svg.plot { max-width: 100%; height: auto; display: block; font-family: "DejaVu Sans", Arial, sans-serif; }
svg .area { fill: #fff; stroke: #333; stroke-width: 1; }
svg .grid { stroke: #dcdfe3; stroke-width: 1; } svg .grid.minor { stroke: #eff1f3; }
svg .tick { font-size: 11px; fill: #333; } svg .alabel { font-size: 12px; fill: #222; }
svg .ptitle { font-size: 13px; font-weight: 700; fill: #111; } svg .legend { font-size: 11px; fill: #222; }
svg .ref { stroke-width: 1.2; stroke-dasharray: 4 3; } svg .reftext { font-size: 11px; }
svg .mark { font-size: 11px; font-weight: 600; } svg .ebar { stroke-width: 1; opacity: .7; }
svg .nodata { font-size: 14px; fill: #999; }
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
}
)CSS";

}  // namespace

Page::Page(const json& passport, const json& analysis, std::string analysis_problem)
    : p_(passport), a_(analysis), analysis_problem_(std::move(analysis_problem)) {}

std::string Page::html() {
  const std::string figs = figures();  // first: fills missing_
  std::ostringstream os;
  os << "<!DOCTYPE html>\n<html lang=\"en\">\n" << head() << "<body>\n<main>\n"
     << identity() << notices() << passport_table() << phases() << figs << captures();
  const std::string dir = text(p_, "out_dir");
  os << "<footer>Generated by " << html_escape("rig " RIG_VERSION) << " from passport.json"
     << (a_.is_object() ? " and analysis.json" : "") << (dir.empty() ? "" : " in " + html_escape(dir))
     << ". Method: docs/method.md (U10/U20, GOST R 8.736-2011, IEEE Std 952/1554).</footer>\n";
  os << "</main>\n</body>\n</html>\n";
  return os.str();
}

std::string Page::head() const {
  const std::string title = "Passport " + text(p_, "serial") + " — " + text(p_, "outcome");
  return "<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
         "<title>" + html_escape(title) + "</title>\n<style>" + kCss + "</style>\n</head>\n";
}

std::string Page::identity() const {
  std::ostringstream os;
  os << "<h1>Acceptance test passport</h1>\n<p class=\"sub\">Quartz pendulum accelerometer with digital feedback "
        "amplifier &middot; U10/U20 method</p>\n";
  os << "<section class=\"ident\"><dl>\n";
  auto row = [&](const char* label, const std::string& value) {
    os << "<dt>" << label << "</dt><dd>" << html_escape(value.empty() ? "—" : value) << "</dd>\n";
  };
  row("Serial number", text(p_, "serial"));
  row("Profile", text(p_, "profile"));
  row("Plant", text(p_, "plant"));
  if (!text(p_, "station").empty()) row("Station", text(p_, "station"));
  row("Software", text(p_, "software"));
  row("Started", text(p_, "started"));
  row("Finished", text(p_, "finished"));
  row("Duration", duration_text(seconds_between(text(p_, "started"), text(p_, "finished"))));
  row("Run folder", text(p_, "out_dir"));
  if (const json* ac = get(p_, {"values", "accuracy_class"}); ac && std::isfinite(number(*ac, "value")))
    row("Accuracy class", text(*ac, "reason") + " (" + fmt_num(number(*ac, "value"), 3) + ")");
  if (!text(p_, "aborted_reason").empty())
    row(text(p_, "outcome") == "ABORTED" ? "Aborted because" : "Stopped because", text(p_, "aborted_reason"));
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
  os << "<table id=\"passport\"><thead><tr><th>Measurement</th><th>Value</th><th>Unit</th><th>Bounds (lo … hi)</th>"
        "<th>Limits</th><th>Outcome</th><th>Reason</th></tr></thead><tbody>\n";
  // The contract's measurements first, in its order, then any others the procedure added.
  std::vector<std::pair<std::string, std::string>> order;
  for (const auto& [name, desc] : descriptions())
    if (values->contains(name)) order.emplace_back(name, desc);
  for (const auto& [name, v] : values->items()) {
    const bool known = std::any_of(descriptions().begin(), descriptions().end(),
                                   [&](const auto& d) { return d.first == name; });
    if (!known) order.emplace_back(name, "");
  }
  for (const auto& [name, desc] : order) {
    const json& v = (*values)[name];
    const std::string outcome = text(v, "outcome");
    os << "<tr" << (outcome == "FAIL" ? " class=\"fail\"" : "") << "><td class=\"name\"><code>" << html_escape(name)
       << "</code>" << (desc.empty() ? "" : "<div>" + html_escape(desc) + "</div>") << "</td>";
    const json* val = get(v, {"value"});
    os << "<td class=\"num\">" << (val && val->is_number() ? fmt_num(val->get<double>(), 5) : html_escape(text(val).empty() ? "—" : text(val)))
       << "</td><td>" << html_escape(text(v, "unit")) << "</td>";
    const double lo = number(v, "lo"), hi = number(v, "hi");
    os << "<td class=\"num\">" << (std::isfinite(lo) || std::isfinite(hi) ? fmt_num(lo) + " … " + fmt_num(hi) : "—")
       << "</td>";
    const json* lim = get(v, {"limits"});
    std::string limits = "—";
    if (lim && lim->is_array() && lim->size() == 2) {
      const double a = number(&(*lim)[0]), b = number(&(*lim)[1]);
      limits = "[" + (std::isfinite(a) ? fmt_num(a) : "−∞") + ", " + (std::isfinite(b) ? fmt_num(b) : "+∞") + "]";
    }
    os << "<td class=\"num\">" << html_escape(limits) << "</td><td>" << badge(outcome) << "</td><td>"
       << html_escape(text(v, "reason")) << "</td></tr>\n";
  }
  os << "</tbody></table>\n";
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
       << "</td><td>" << html_escape(text(x, "started")) << "</td><td>" << html_escape(text(x, "finished"))
       << "</td><td>" << html_escape(text(x, "message")) << "</td></tr>\n";
  }
  os << "</tbody></table>\n";
  return os.str();
}

std::string Page::captures() const {
  const json* c = get(p_, {"captures"});
  if (!c || !c->is_array() || c->empty()) return "";
  std::ostringstream os;
  os << "<h2>Captures</h2>\n<p>Raw recordings in the run folder (rig capture format; <code>rig analyze FILE "
        "--input capture</code> re-analyses one):</p><ul id=\"captures\">\n";
  for (const json& x : *c) os << "<li><code>" << html_escape(text(&x)) << "</code></li>\n";
  os << "</ul>\n";
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
  Plot p;
  p.id = "allan-" + ch;
  p.title = "Overlapping Allan deviation, " + what;
  p.x_label = "τ, s";
  p.y_label = "σ(τ), g";
  p.log_x = p.log_y = true;
  Series dev{"OADEV with 68 % bounds", field(od, "tau_s"), field(od, "dev"), field(od, "lo"), field(od, "hi"),
             ch == "x" ? kBlue : kGreen, Series::Style::line_markers, false, 1.5};
  p.series.push_back(dev);
  double tmin = kNaN, tmax = kNaN;
  for (double t : dev.x)
    if (t > 0) {
      tmin = std::isnan(tmin) ? t : std::min(tmin, t);
      tmax = std::isnan(tmax) ? t : std::max(tmax, t);
    }
  const std::vector<double> grid = log_grid(tmin, tmax, 80);
  std::string terms_caption;

  const json* nt = get(*al, {"noise_terms"});
  if (nt) {
    // Each identified term's asymptote (IEEE 952 slope relations).
    const std::vector<std::pair<std::string, const char*>> terms = {
        {"Q", kPurple}, {"N", kOrange}, {"B", kRed}, {"K", kBrown}, {"R", kGrey}};
    for (const auto& [term, color] : terms) {
      const json* t = get(*nt, {term.c_str()});
      const double v = seconds_basis(term, number(t ? get(*t, {"value"}) : nullptr), t ? text(*t, "unit") : "");
      if (!std::isfinite(v) || v <= 0) continue;
      Series s{term + " = " + fmt_num(number(get(*t, {"value"})), 3) + " " + text(*t, "unit"), grid, {}, {}, {},
               color, Series::Style::line, true, 1.2, false};
      for (double tau : grid) s.y.push_back(term_sigma(term, v, tau));
      p.series.push_back(std::move(s));
    }
    // Least-squares sum of all terms: σ² = Σ σ_term².
    if (const json* lsq = get(*nt, {"lsq_fit"}); lsq && lsq->is_object()) {
      Series s{"least-squares fit of all terms", grid, {}, {}, {}, "#222", Series::Style::line, false, 1.0, false};
      bool any = false;
      for (double tau : grid) {
        double var = 0;
        for (const char* term : {"Q", "N", "B", "K", "R"}) {
          const double c = number(*lsq, term);
          if (std::isfinite(c)) {
            var += std::pow(term_sigma(term, c, tau), 2);
            any = true;
          }
        }
        s.y.push_back(any ? std::sqrt(var) : kNaN);
      }
      if (any) p.series.push_back(std::move(s));
    }
    // The paper's method: 4th-degree polynomial in log-log and its straight segments.
    if (const json* pf = get(*nt, {"paper_fit"})) {
      const std::vector<double> c = numbers(get(*pf, {"poly"}));
      if (!c.empty()) {
        Series s{"4th-degree polynomial (paper)", grid, {}, {}, {}, "#17becf", Series::Style::line, false, 1.2, false};
        for (double tau : grid) {
          double lx = std::log10(tau), ly = 0, pw = 1;
          for (double ci : c) {
            ly += ci * pw;
            pw *= lx;
          }
          s.y.push_back(std::pow(10.0, ly));
        }
        p.series.push_back(std::move(s));
      }
      if (const json* segs = get(*pf, {"segments"}); segs && segs->is_array()) {
        int k = 0;
        for (const json& sg : *segs) {
          const double a = number(sg, "tau_from_s"), b = number(sg, "tau_to_s"), slope = number(sg, "slope"),
                       tm = number(sg, "tau_mid_s"), sm = number(sg, "sigma_mid");
          if (!(a > 0 && b > a && tm > 0 && sm > 0 && std::isfinite(slope))) continue;
          Series s{k++ == 0 ? "polynomial segments (slope at τ_mid)" : "", {a, b},
                   {sm * std::pow(a / tm, slope), sm * std::pow(b / tm, slope)}, {}, {}, "#e377c2",
                   Series::Style::line, false, 3.0, false};
          p.series.push_back(std::move(s));
          p.markers.push_back({tm, sm, "a = " + fmt_num(slope, 2), "#e377c2"});
        }
      }
    }
    const double tau_cp = number(*nt, "tau_cp_s");
    const double b = number(get(*nt, {"B", "value"}));
    if (tau_cp > 0) {
      p.lines.push_back({true, tau_cp, "τ_ср = " + fmt_num(tau_cp, 3) + " s", kRed});
      if (b > 0) p.markers.push_back({tau_cp, 0.664 * b, "B = " + fmt_num(b, 3) + " g", kRed, true});
    }
    terms_caption = " Dashed: each identified noise term's asymptote (Q −1, N −½, B 0, K +½, R +1).";
    if (const json* r = get(*nt, {"R"}); r && !text(*r, "reason").empty())
      terms_caption += " R: " + html_escape(text(*r, "reason")) + ".";
  }
  return figure(to_svg(p), "Allan deviation of the " + html_escape(what) + " with 68 % confidence bounds." +
                               terms_caption + " B = σ(τ_ср)/0.664 (docs/method.md, IEEE Std 952).") +
         (nt ? terms_table(*nt, ch) : "");
}

std::string Page::psd(const std::string& ch) {
  const std::string what = ch == "x" ? "raw output x(t)" : "filtered output y(t)";
  const json* ps = get(a_, {"psd", ch.c_str()});
  if (!ps || !get(*ps, {"f_hz"})) {
    if (a_.is_object()) missing_.push_back("power spectral density of the " + what + " (analysis.json psd." + ch + ")");
    return "";
  }
  Plot p;
  p.id = "psd-" + ch;
  p.title = "Power spectral density, " + what;
  p.x_label = "f, Hz";
  const std::string unit = text(*ps, "unit").empty() ? "g^2/Hz" : text(*ps, "unit");
  p.y_label = "PSD, " + unit;
  p.log_x = p.log_y = true;
  p.series.push_back({"PSD (" + ch + ")", numbers(get(*ps, {"f_hz"})), numbers(get(*ps, {"psd"})), {}, {},
                      ch == "x" ? kBlue : kGreen, Series::Style::line, false, 1.0});
  if (const json* pk = get(*ps, {"peaks"}); pk && pk->is_array())
    for (const json& k : *pk) p.markers.push_back({number(k, "f_hz"), number(k, "psd"), fmt_num(number(k, "f_hz"), 4) + " Hz", kRed});
  return figure(to_svg(p), "PSD (Welch) of the " + html_escape(what) +
                               "; labelled: detected peaks (building vibration near 70–76 Hz, interference near the 1 "
                               "kHz polling rate).");
}

std::string Page::timeseries() {
  const json* ts = get(a_, {"timeseries"});
  if (!ts) {
    if (a_.is_object()) missing_.push_back("raw and filtered output over time (analysis.json timeseries)");
    return "";
  }
  const double rate = number(*ts, "rate_hz"), t0 = std::isfinite(number(*ts, "t0_s")) ? number(*ts, "t0_s") : 0.0;
  const std::vector<double> x = numbers(get(*ts, {"x"})), y = numbers(get(*ts, {"y"}));
  if (!(rate > 0)) {
    missing_.push_back("timeseries.rate_hz (output over time not drawn)");
    return "";
  }
  std::vector<double> t(std::max(x.size(), y.size()));
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = t0 + static_cast<double>(i) / rate;
  Plot p;
  p.id = "timeseries";
  p.title = "Output over time: raw x(t) and filtered y(t)";
  p.x_label = "t, s";
  p.y_label = "output, g";
  p.series.push_back({"x(t), no filter", {t.begin(), t.begin() + static_cast<std::ptrdiff_t>(x.size())}, x, {}, {},
                      "#9ecae1", Series::Style::line, false, 0.8});
  p.series.push_back({"y(t), with the output filter", {t.begin(), t.begin() + static_cast<std::ptrdiff_t>(y.size())},
                      y, {}, {}, "#08519c", Series::Style::line, false, 1.0});
  const std::string note = text(*ts, "note");
  return figure(to_svg(p), "Raw and filtered output (cf. the paper's Fig. 5)" +
                               (note.empty() ? std::string(".") : ": " + html_escape(note) + "."));
}

std::string Page::averages() {
  const json* runs = get(a_, {"runs"});
  if (!runs || !runs->is_array() || runs->empty()) {
    if (a_.is_object()) missing_.push_back("the 100 s averages of the U10/U20 runs (analysis.json runs)");
    return "";
  }
  Plot p;
  p.id = "averages";
  p.title = "100 s averages of the U10 and U20 runs";
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
  Plot p;
  p.id = "in-run";
  p.title = "In-run zero signal, block averages of the 30 min U10 run";
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
  if (ts > 0) p.lines.push_back({true, ts, "t_рег = " + fmt_num(ts, 3) + " s", kRed});
  return figure(to_svg(p), "Step response (cf. the paper's Fig. 6).");
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
