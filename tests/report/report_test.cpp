// report.html from a generated run folder: content, escaping, partial and missing inputs,
// and the SVG writer's axes and decimation. The browser check is in browser_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>


#include "app/commands.hpp"
#include "rig/core/errors.hpp"
#include "rig/report/bounded.hpp"
#include "rig/report/passport_read.hpp"
#include "rig/report/passport_check.hpp"
#include "rig/report/report.hpp"
#include "rig/report/svg_plot.hpp"
#include "rig/report/svg.hpp"
#include "tests/report/fixture.hpp"

namespace {

using nlohmann::json;
using rig::test::TempDir;

using rig::test::slurp;

std::size_t count(const std::string& hay, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + 1)) ++n;
  return n;
}

const char* const kPlots[] = {"allan-x", "allan-y", "psd-x",  "psd-y", "timeseries", "timeseries-range",
                              "averages", "in-run",  "step", "freq"};

TEST(Report, FullRunHasIdentityTableAndEveryPlot) {
  TempDir d;
  const json a = rig::test::fixture_analysis();
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  const std::string out = rig::report::write_report(d.path.string());
  EXPECT_EQ(out, (d.path / "report.html").string());
  const std::string h = slurp(out);
  EXPECT_EQ(h.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(h.find("QA-0042"), std::string::npos);
  EXPECT_NE(h.find("<span class=\"badge pass\">PASS</span>"), std::string::npos);
  EXPECT_NE(h.find("1 h 52 min 31 s"), std::string::npos);  // duration from started/finished
  for (const char* name : {"bias", "base_error", "in_run_b_gost_100s", "in_run_b_allan", "tau_cp", "q", "n", "k", "r",
                           "rms_filtered", "bandwidth_0p5", "settling_time", "accuracy_class"})
    EXPECT_NE(h.find("<code>" + std::string(name) + "</code>"), std::string::npos) << name;
  EXPECT_NE(h.find("-0.00050137"), std::string::npos);               // bias value
  // Bounds, to the digits their half-width (0.35e-6) supports: two, the value alike.
  EXPECT_NE(h.find("1.80e-06 …</span> <span class=\"nw\">2.50e-06"), std::string::npos);
  EXPECT_NE(h.find(">2.10e-06</td>"), std::string::npos);  // in_run_b_allan's value
  EXPECT_NE(h.find("[−∞, 5e-06]"), std::string::npos);               // one-sided limit
  EXPECT_NE(h.find("needs a record longer than 50 h"), std::string::npos);  // r's reason
  // Contract order: bias before base_error before accuracy_class (not alphabetical).
  EXPECT_LT(h.find("<code>bias</code>"), h.find("<code>base_error</code>"));
  EXPECT_LT(h.find("<code>settling_time</code>"), h.find("<code>accuracy_class</code>"));
  for (const char* id : kPlots) EXPECT_EQ(count(h, "data-plot=\"" + std::string(id) + "\""), 1u) << id;
  EXPECT_NE(h.find("τ_ср = 200 s"), std::string::npos);
  EXPECT_NE(h.find(">72 Hz or 928 Hz<"), std::string::npos);  // labelled PSD peak, and its alias at 1 kHz
  EXPECT_NE(h.find("f_пп = 492 Hz"), std::string::npos);
  EXPECT_NE(h.find("captures/in-run-U10.cap"), std::string::npos);
  EXPECT_EQ(h.find("id=\"missing\""), std::string::npos);  // nothing missing
  // Self-contained and printable: no scripts, no external resources, an A4 print sheet.
  EXPECT_EQ(h.find("<script"), std::string::npos);
  for (const char* attr : {"src=", "href=", "url(http", "@import"}) EXPECT_EQ(h.find(attr), std::string::npos) << attr;
  EXPECT_NE(h.find("@page { size: A4"), std::string::npos);
  EXPECT_NE(h.find("@media print"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(d.path / "report.html.tmp"));
}

// A page that cannot be written says why, as the system does (it said only "cannot write the
// report": a review); a folder of that name stands where the page's temporary file goes (root
// writes through any permission, this fails for every user).
TEST(Report, APageThatCannotBeWrittenSaysWhy) {
  TempDir d;
  const json a = rig::test::fixture_analysis();
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  std::filesystem::create_directories(d.path / "report.html.tmp" / "kept");
  try {
    rig::report::write_report(d.path.string());
    FAIL() << "written";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("report.html.tmp: cannot write the report (Is a directory)"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(d.path / "report.html"));
  EXPECT_TRUE(std::filesystem::exists(d.path / "report.html.tmp" / "kept")) << "nothing of the user's removed";
}

// The <svg> element of one plot and the caption of its figure.
std::string plot_svg(const std::string& h, const std::string& id) {
  const std::size_t at = h.find("data-plot=\"" + id + "\"");
  if (at == std::string::npos) return "";
  return h.substr(h.rfind("<svg", at), h.find("</svg>", at) - h.rfind("<svg", at));
}
std::string caption_of(const std::string& h, const std::string& id) {
  const std::size_t at = h.find("data-plot=\"" + id + "\"");
  if (at == std::string::npos) return "";
  const std::size_t c = h.find("<figcaption", at);
  return h.substr(c, h.find("</figcaption>", c) - c);
}
// The texts of the elements of `cls` in an SVG, in order.
std::vector<std::string> texts_of_class(const std::string& svg, const std::string& cls) {
  std::vector<std::string> out;
  for (std::size_t at = svg.find("class=\"" + cls + "\""); at != std::string::npos;
       at = svg.find("class=\"" + cls + "\"", at + 1)) {
    const std::size_t t0 = svg.find('>', at) + 1;
    out.push_back(svg.substr(t0, svg.find('<', t0) - t0));
  }
  return out;
}
// The row of the passport table for one measurement.
std::string row_of(const std::string& h, const std::string& name) {
  const std::size_t at = h.find("<code>" + name + "</code>");
  if (at == std::string::npos) return "";
  return h.substr(at, h.find("</tr>", at) - at);
}

TEST(Report, PassportHasFirmwareTemperatureDeviceTimeAndSignatures) {
  const std::string h = rig::report::render_report(rig::test::fixture_passport(), rig::test::fixture_analysis());
  EXPECT_NE(h.find("<dt>DUT firmware</dt><dd>1.4.0</dd>"), std::string::npos);
  EXPECT_NE(h.find("<dt>DUT temperature</dt><dd>22.5 °C"), std::string::npos);
  // Wall time from started/finished and device time from the rig clock, side by side.
  EXPECT_NE(h.find("<dt>Wall time</dt><dd>1 h 52 min 31 s</dd>\n<dt>Device time</dt><dd>1 h 53 min 59 s</dd>"),
            std::string::npos);
  // A paper passport's sign-off: who tested, who checked, with name, signature and date.
  const std::size_t sig = h.find("id=\"signatures\"");
  ASSERT_NE(sig, std::string::npos);
  const std::string block = h.substr(sig, h.find("</section>", sig) - sig);
  for (const char* cell : {">Tested by<", ">Checked by<", ">Name<", ">Signature<", ">Date<"})
    EXPECT_NE(block.find(cell), std::string::npos) << cell;
  EXPECT_LT(h.find("id=\"passport\""), sig);  // after the measurements it signs for
}

TEST(Report, GostRowsNameTheBlockLengthActuallyUsed) {
  // The ci profile: values named ..._100s/_200s hold 2 s and 4 s blocks.
  json a = rig::test::fixture_analysis();
  a["in_run"]["blocks"][0]["block_s"] = 2.0;
  a["in_run"]["blocks"][1]["block_s"] = 4.0;
  a["in_run"]["n"] = 40000;
  const std::string h = rig::report::render_report(rig::test::fixture_passport(), a);
  EXPECT_NE(row_of(h, "in_run_b_gost_100s").find("of 2 s block means"), std::string::npos) << row_of(h, "in_run_b_gost_100s");
  EXPECT_NE(row_of(h, "in_run_b_gost_200s").find("of 4 s block means"), std::string::npos);
  EXPECT_NE(row_of(h, "accuracy_class").find("B of the 2 s blocks"), std::string::npos);
  EXPECT_EQ(row_of(h, "in_run_b_gost_100s").find("100 s"), std::string::npos);
  EXPECT_NE(h.find("2 s blocks, B = "), std::string::npos);            // the in-run plot's legend
  EXPECT_NE(h.find("block averages of the 40 s in-run record"), std::string::npos);
  // A name that states its length is matched by the length, wherever its block is.
  json p = rig::test::fixture_passport();
  p["values"]["in_run_b_gost_4s"] = p["values"]["in_run_b_gost_200s"];
  p["values"].erase("in_run_b_gost_200s");
  std::swap(a["in_run"]["blocks"][0], a["in_run"]["blocks"][1]);
  const std::string g = rig::report::render_report(p, a);
  EXPECT_NE(row_of(g, "in_run_b_gost_4s").find("of 4 s block means"), std::string::npos);
  // The full run: 100 s runs read from their samples.
  EXPECT_NE(g.find("100 s averages of the U10 and U20 runs"), std::string::npos);
}

TEST(Report, PsdCaptionNamesExactlyTheLabelledPeaks) {
  json a = rig::test::fixture_analysis();
  // A crowded spectrum: more close peaks than there is room to label.
  for (double f = 100; f < 112; f += 0.5) a["psd"]["y"]["peaks"].push_back({{"f_hz", f}, {"psd", 1e-8}});
  const std::string h = rig::report::render_report(rig::test::fixture_passport(), a);
  for (const char* id : {"psd-x", "psd-y"}) {
    std::vector<std::string> labels = texts_of_class(plot_svg(h, id), "mark");
    ASSERT_FALSE(labels.empty()) << id;
    std::sort(labels.begin(), labels.end(),
              [](const std::string& l, const std::string& r) { return std::stod(l) < std::stod(r); });
    std::string joined;
    for (const std::string& l : labels) joined += (joined.empty() ? "" : ", ") + l;
    const std::string cap = caption_of(h, id);
    EXPECT_NE(cap.find("data-peaks=\"" + joined + "\""), std::string::npos) << id << ": " << cap;
    EXPECT_NE(cap.find("labelled peaks: " + joined + "."), std::string::npos) << id << ": " << cap;
  }
  EXPECT_NE(caption_of(h, "psd-y").find("circled without a label"), std::string::npos);
  EXPECT_EQ(caption_of(h, "psd-x").find("circled without a label"), std::string::npos);
  EXPECT_EQ(h.find("building vibration"), std::string::npos);  // no claim the data do not make
}

TEST(Report, NoiseTermsAreQuotedInThePassportsPerHourUnits) {
  const std::string h = rig::report::render_report(rig::test::fixture_passport(), rig::test::fixture_analysis());
  // analysis.json holds the seconds basis too; the page shows only the passport's units.
  for (const char* seconds : {"g*s", "g/s"}) EXPECT_EQ(h.find(seconds), std::string::npos) << seconds;
  for (const char* hours : {"g*h^0.5", "g/h^0.5"}) {
    EXPECT_NE(h.find("<td>" + std::string(hours) + "</td>"), std::string::npos) << hours;  // tables
    EXPECT_NE(plot_svg(h, "allan-x").find(hours), std::string::npos) << hours;             // legend
  }
  // N of the terms table equals the passport's n (2.2306e-7 g*h^0.5) in value and unit, to the
  // digits its ±10 % bounds support (half-width 2.2e-8: the 1e-9 digit).
  const std::size_t terms = h.find("id=\"terms-x\"");
  ASSERT_NE(terms, std::string::npos);
  const std::string n_row = h.substr(h.find("N — random walk", terms), 300);
  EXPECT_NE(n_row.find(">2.23e-07</td><td>g*h^0.5<"), std::string::npos) << n_row;
  EXPECT_NE(n_row.find(">2.01e-07 …</span> <span class=\"nw\">2.45e-07<"), std::string::npos) << n_row;
  EXPECT_NE(plot_svg(h, "allan-x").find("τ, s"), std::string::npos);  // τ stays in seconds
}

TEST(Report, EveryBoundsCellStatesItsIntervalLevel) {
  json p = rig::test::fixture_passport();
  p["values"]["bias"]["lo"] = -5.1e-4;
  p["values"]["bias"]["hi"] = -4.9e-4;
  p["values"]["n"]["lo"] = 2.0e-7;
  p["values"]["n"]["hi"] = 2.4e-7;
  p["values"]["extra"] = {{"value", 1}, {"lo", 0.5}, {"hi", 1.5}, {"confidence", 0.9}};
  // R read from the record's drift: its interval is Student's t on the drift, not the Allan fit's.
  p["values"]["r"]["value"] = 2e-5;
  p["values"]["r"]["lo"] = 1.2e-5;
  p["values"]["r"]["hi"] = 2.8e-5;
  p["values"]["r"]["reason"] = "least-squares drift of the record (falling; ..., Student's t at EDF 12)";
  const std::string h = rig::report::render_report(p, rig::test::fixture_analysis());
  EXPECT_NE(row_of(h, "r").find("<div class=\"lvl\">68 %, ±1 σ of the record&#39;s drift (Student&#39;s t)</div>"),
            std::string::npos)
      << row_of(h, "r");
  EXPECT_NE(row_of(h, "bias").find("<div class=\"lvl\">95 %, GOST R 8.736</div>"), std::string::npos);
  EXPECT_NE(row_of(h, "n").find("<div class=\"lvl\">68 %, ±1 σ of the Allan fit</div>"), std::string::npos);
  EXPECT_NE(row_of(h, "in_run_b_allan").find("68 %"), std::string::npos);
  // The paper's B: one Allan point's chi-square interval, its lower end the model's where other
  // terms add to the point (a metrologist's review: it was labelled the fit's one sigma).
  p["values"]["in_run_b_allan"]["reason"] =
      "paper polynomial: no flat segment between inflections; tau_cp at its minimum; flicker is 35 % of the model's "
      "sigma^2 at tau_cp: sigma(tau_cp)/0.664 bounds B from above, the lower bound is the model's";
  EXPECT_NE(rig::report::render_report(p, rig::test::fixture_analysis())
                .find("<div class=\"lvl\">68 %: χ² upper end of σ(τ_ср)/0.664, lower end the noise model&#39;s B</div>"),
            std::string::npos);
  p["values"]["in_run_b_allan"]["reason"] = "paper: sigma(tau_cp) / 0.664, tau_cp the middle of the flat segment tau = 10..40 s";
  p["values"]["in_run_b_allan_filtered"] = p["values"]["in_run_b_allan"];
  p["values"]["in_run_b_allan_filtered"]["reason"] =
      "on the filtered output y(t); paper: sigma(tau_cp) / 0.664, tau_cp the middle of the flat segment tau = 10..40 s";
  EXPECT_NE(row_of(rig::report::render_report(p, rig::test::fixture_analysis()), "in_run_b_allan_filtered")
                .find("<div class=\"lvl\">68 %, χ² interval of σ(τ_ср)/0.664 at its EDF</div>"),
            std::string::npos);
  EXPECT_NE(rig::report::render_report(p, rig::test::fixture_analysis())
                .find("<div class=\"lvl\">68 %, χ² interval of σ(τ_ср)/0.664 at its EDF</div>"),
            std::string::npos);
  EXPECT_NE(row_of(h, "extra").find("<div class=\"lvl\">90 %</div>"), std::string::npos);  // the passport's own
  EXPECT_EQ(row_of(h, "rms_filtered").find("class=\"lvl\""), std::string::npos);          // no bounds, no level
  // Every row with bounds has its level.
  const std::size_t t0 = h.find("id=\"passport\""), t1 = h.find("</table>", t0);
  const std::string table = h.substr(t0, t1 - t0);
  EXPECT_EQ(count(table, " …</span>"), count(table, "class=\"lvl\""));
  EXPECT_NE(caption_of(h, "allan-x").find("68.3 % confidence bounds"), std::string::npos);
}

// The passport's top-level `skipped` (a DUT with [dut] commands = false) is listed, step and
// reason, in its own section; a passport without it has no such section.
TEST(Report, SkippedStepsAreListedAndAbsentWithoutAny) {
  json p = rig::test::fixture_passport();
  const std::string none = rig::report::render_report(p, rig::test::fixture_analysis());
  EXPECT_EQ(none.find("Skipped steps"), std::string::npos);
  EXPECT_EQ(none.find("id=\"skipped\""), std::string::npos);
  p["skipped"] = json::array({{{"step", "identify"}, {"reason", "[dut] commands = false: no command channel"}},
                              {{"step", "loop test"}, {"reason", "no <command> channel & no LOOP_TEST"}}});
  const std::string h = rig::report::render_report(p, rig::test::fixture_analysis());
  const std::size_t at = h.find("<h2>Skipped steps</h2>");
  ASSERT_NE(at, std::string::npos);
  const std::string table = h.substr(at, h.find("</table>", at) - at);
  EXPECT_NE(table.find("<tr><td>identify</td><td>[dut] commands = false: no command channel</td></tr>"),
            std::string::npos) << table;
  EXPECT_NE(table.find("<tr><td>loop test</td><td>no &lt;command&gt; channel &amp; no LOOP_TEST</td></tr>"),
            std::string::npos) << table;
  // On page 1, after the measurements whose null values it explains, before the sign-off.
  EXPECT_LT(h.find("id=\"passport\""), at);
  EXPECT_LT(at, h.find("id=\"signatures\""));
  p["skipped"] = json::array();
  EXPECT_EQ(rig::report::render_report(p, rig::test::fixture_analysis()).find("Skipped steps"), std::string::npos);
}

// A failed value is quoted with the digits that put it outside its limits, whatever its
// bounds support (the page read 0.00314 against [0, 0.00314]: an automation review).
TEST(Report, AFailedValueShowsTheDigitsThatPutItOutside) {
  json p = rig::test::fixture_passport();
  p["values"]["settling_time"]["value"] = 0.0031400000000000004;
  p["values"]["settling_time"]["lo"] = 0.0028928;
  p["values"]["settling_time"]["hi"] = 0.0033872;
  p["values"]["settling_time"]["limits"] = json::array({0.0, 0.00314});
  p["values"]["settling_time"]["outcome"] = "FAIL";
  const std::string h = rig::report::render_report(p, rig::test::fixture_analysis());
  const std::size_t at = h.find("<code>settling_time</code>");
  ASSERT_NE(at, std::string::npos);
  const std::string row = h.substr(at, h.find("</tr>", at) - at);
  EXPECT_NE(row.find(">0.0031400000000000004<"), std::string::npos) << row;
  EXPECT_NE(row.find(">[0, 0.00314]<"), std::string::npos) << row;
}

// A passing value whose rounding puts it beside its limits on the wrong side is shown with the
// digits that put it inside (the page read 0.0024224 against [0, 0.002422]: a metrologist's review).
TEST(Report, APassingValueNearItsLimitReadsAsInside) {
  json p = rig::test::fixture_passport();
  p["values"]["settling_time"]["value"] = 0.00242236;
  p["values"]["settling_time"]["lo"] = nullptr;
  p["values"]["settling_time"]["hi"] = nullptr;
  p["values"]["settling_time"]["limits"] = json::array({0.0, 0.0024224});
  p["values"]["settling_time"]["outcome"] = "PASS";
  const std::string h = rig::report::render_report(p, rig::test::fixture_analysis());
  const std::size_t at = h.find("<code>settling_time</code>");
  ASSERT_NE(at, std::string::npos);
  const std::string row = h.substr(at, h.find("</tr>", at) - at);
  EXPECT_NE(row.find(">0.0024224<"), std::string::npos) << row;  // 5 digits, and the limit with its own
  EXPECT_NE(row.find(">[0, 0.0024224]<"), std::string::npos) << row;
}

// Page 1 quotes a value with bounds to the digits the bounds support (two significant digits
// of the half-width, the value and both bounds to the same digit); a value without bounds keeps
// its five significant digits; passport.json is not touched (the page reads it).
TEST(Report, ValuesWithBoundsShowOnlyTheDigitsTheirBoundsSupport) {
  json p = rig::test::fixture_passport();
  p["values"]["bias"]["value"] = -5.01372918e-4;
  p["values"]["bias"]["lo"] = -5.1146e-4;  // half-width 9.96e-6: "1.0e-05", the 1e-6 digit
  p["values"]["bias"]["hi"] = -4.9154e-4;
  p["values"]["bandwidth_0p5"]["lo"] = 487.31;  // half-width 9.3 Hz: the 0.1 Hz digit
  p["values"]["bandwidth_0p5"]["hi"] = 505.93;
  p["values"]["bandwidth_0p5"]["value"] = 492.123456;
  const std::string h = rig::report::render_report(p, rig::test::fixture_analysis());
  const std::string bias = row_of(h, "bias");
  EXPECT_NE(bias.find(">-0.000501</td>"), std::string::npos) << bias;
  EXPECT_NE(bias.find(">-0.000511 …</span> <span class=\"nw\">-0.000492<"), std::string::npos) << bias;
  const std::string bw = row_of(h, "bandwidth_0p5");
  EXPECT_NE(bw.find(">492.1</td>"), std::string::npos) << bw;
  EXPECT_NE(bw.find(">487.3 …</span> <span class=\"nw\">505.9<"), std::string::npos) << bw;
  // Without bounds: as before.
  EXPECT_NE(row_of(h, "base_error").find(">0.00038549</td>"), std::string::npos) << row_of(h, "base_error");
  EXPECT_NE(row_of(h, "rms_filtered").find(">0.0448</td>"), std::string::npos);
  // One bound only gives no width: the value keeps its digits.
  p["values"]["bias"]["hi"] = nullptr;
  const std::string one = row_of(rig::report::render_report(p, rig::test::fixture_analysis()), "bias");
  EXPECT_NE(one.find(">-0.00050137</td>"), std::string::npos) << one;
}

TEST(Bounded, RoundsToTwoSignificantDigitsOfTheHalfWidth) {
  using rig::report::round_to_bounds;
  auto r = round_to_bounds(2.1e-6, 1.8e-6, 2.5e-6);  // half-width 3.5e-7
  ASSERT_TRUE(r);
  EXPECT_EQ(r->value, "2.10e-06");
  EXPECT_EQ(r->lo, "1.80e-06");
  EXPECT_EQ(r->hi, "2.50e-06");
  r = round_to_bounds(1234.5678, 1200.0, 1270.0);  // half-width 35: the units digit
  ASSERT_TRUE(r);
  EXPECT_EQ(r->value, "1235");
  EXPECT_EQ(r->lo, "1200");
  EXPECT_EQ(r->hi, "1270");
  r = round_to_bounds(0.123456, 0.1, 0.15);  // half-width 0.025: the 0.001 digit, zeros kept
  ASSERT_TRUE(r);
  EXPECT_EQ(r->value, "0.123");
  EXPECT_EQ(r->lo, "0.100");
  EXPECT_EQ(r->hi, "0.150");
  r = round_to_bounds(9.996e-7, 9.0e-7, 1.1e-6);  // half-width 1.0e-7; the value rounds up a decade
  ASSERT_TRUE(r);
  EXPECT_EQ(r->value, "1.00e-06");
  r = round_to_bounds(3e-9, -2e-6, 2e-6);  // a value smaller than the last digit kept
  ASSERT_TRUE(r);
  EXPECT_EQ(r->value, "0");
  EXPECT_EQ(r->lo, "-2.0e-06");
  const double nan = std::nan("");
  EXPECT_FALSE(round_to_bounds(1.0, nan, 2.0));
  EXPECT_FALSE(round_to_bounds(1.0, 0.5, INFINITY));
  EXPECT_FALSE(round_to_bounds(1.0, 1.0, 1.0));  // no width
  EXPECT_FALSE(round_to_bounds(1.0, 2.0, 0.5));
  EXPECT_FALSE(round_to_bounds(nan, 0.5, 1.5));
}

// A PSD peak at f of a record sampled at fs may be a line at fs − f folded by the sampling:
// the label names both (the rig does not know what lies above Nyquist) and the caption says
// why; without the rate (no timeseries.rate_hz) no alias is claimed.
TEST(Report, PsdPeakLabelsNameTheAliasAtTheSamplingRate) {
  json a = rig::test::fixture_analysis();  // sampled at 1000 Hz; peaks at 72 and 470 Hz
  const std::string h = rig::report::render_report(rig::test::fixture_passport(), a);
  const std::vector<std::string> labels = texts_of_class(plot_svg(h, "psd-x"), "mark");
  EXPECT_NE(std::find(labels.begin(), labels.end(), "72 Hz or 928 Hz"), labels.end());
  EXPECT_NE(std::find(labels.begin(), labels.end(), "470 Hz or 530 Hz"), labels.end());
  EXPECT_NE(caption_of(h, "psd-x").find("give the same samples (aliasing)"), std::string::npos) << caption_of(h, "psd-x");
  EXPECT_EQ(rig::report::peak_label(500, 1000), "500 Hz");  // at Nyquist f = fs − f
  EXPECT_EQ(rig::report::peak_label(72, std::nan("")), "72 Hz");
  a["timeseries"].erase("rate_hz");
  const std::string u = rig::report::render_report(rig::test::fixture_passport(), a);
  const std::vector<std::string> plain = texts_of_class(plot_svg(u, "psd-x"), "mark");
  EXPECT_NE(std::find(plain.begin(), plain.end(), "72 Hz"), plain.end());
  EXPECT_EQ(u.find(" or 928 Hz"), std::string::npos);
  EXPECT_EQ(caption_of(u, "psd-x").find("aliasing"), std::string::npos);
}

TEST(Report, StepAxisSpansThreeSettlingTimes) {
  json a = rig::test::fixture_analysis();  // the step is recorded for 10 ms
  a["loop"]["settling_time_s"] = 0.001;
  const std::string svg = plot_svg(rig::report::render_report(rig::test::fixture_passport(), a), "step");
  double last = 0;
  for (std::size_t at = svg.find("text-anchor=\"middle\" class=\"tick\">"); at != std::string::npos;
       at = svg.find("text-anchor=\"middle\" class=\"tick\">", at + 1))
    last = std::stod(svg.substr(svg.find('>', at) + 1));
  EXPECT_GT(last, 0.0025);
  EXPECT_LE(last, 0.0031);  // not the record's 0.01 s
  EXPECT_NE(svg.find("t_рег = 0.001 s"), std::string::npos);
  EXPECT_NE(svg.find(">+5 %<"), std::string::npos);  // the settling band
}

TEST(Report, OutputOverTimeIsBlockMeansWithTheRawEnvelope) {
  const json a = rig::test::fixture_analysis();
  const std::string h = rig::report::render_report(rig::test::fixture_passport(), a);
  // The means on their own scale, then the raw extremes around them.
  const std::string means = plot_svg(h, "timeseries"), range = plot_svg(h, "timeseries-range");
  EXPECT_EQ(count(means, "<polygon"), 0u);
  EXPECT_EQ(count(means, "<polyline"), 2u);  // x and y block means
  EXPECT_EQ(count(range, "<polygon"), 2u);   // x and y min/max bands
  EXPECT_EQ(count(range, "<polyline"), 2u);  // with the means
  EXPECT_NE(means.find("0.06 s block means"), std::string::npos);
  EXPECT_NE(caption_of(h, "timeseries").find("drift"), std::string::npos);
  // The whole 60 s capture is drawn, not its first 2 s.
  for (const std::string* svg : {&means, &range}) EXPECT_NE(svg->find(">60<"), std::string::npos);
  // The means' axis is scaled to the means, not to the raw spread around them.
  auto y_top = [](const std::string& svg) {
    double top = 0;
    const std::string y_tick = "text-anchor=\"end\" class=\"tick\">";
    for (std::size_t at = svg.find(y_tick); at != std::string::npos; at = svg.find(y_tick, at + 1))
      top = std::max(top, std::abs(std::stod(svg.substr(at + y_tick.size()))));
    return top;
  };
  EXPECT_LT(y_top(means), y_top(range) / 3);
}

TEST(Report, DurationHonoursTimeZones) {
  json p = rig::test::fixture_passport();
  p["finished"] = "2026-11-20T11:52:31+03:00";  // = 08:52:31Z
  p["station"] = "line-2-rig-1";
  const std::string h = rig::report::render_report(p, json());
  EXPECT_NE(h.find("0 h 52 min 31 s"), std::string::npos);
  EXPECT_NE(h.find("line-2-rig-1"), std::string::npos);
  EXPECT_NE(h.find("precision (2)"), std::string::npos);  // accuracy class in the identity block
  p["values"]["accuracy_class"]["value"] = nullptr;      // not measured: no such row
  p["outcome"] = "ERROR";
  p["aborted_reason"] = "DUT link lost";
  const std::string e = rig::report::render_report(p, json());
  EXPECT_EQ(e.find("<dt>Accuracy class</dt>"), std::string::npos);
  EXPECT_NE(e.find("<dt>Why it ended</dt><dd class=\"wrap\">DUT link lost</dd>"), std::string::npos);
}

TEST(Report, EscapesEveryTextFromTheRunFolder) {
  TempDir d;
  json p = rig::test::fixture_passport("<script>alert('x')</script>&\"", "FAIL");
  p["values"]["bias"]["reason"] = "<b>bold</b> & \"quoted\"";
  p["values"]["bias"]["outcome"] = "FAIL";
  p["values"]["bias"]["value"] = -2e-3;  // outside its limits, as a FAIL is
  p["values"]["<img src=x>"] = {{"value", 1}, {"unit", "<u>"}, {"outcome", "PASS"}};
  p["phases"][0]["message"] = "</td><script>";
  p["captures"].push_back("captures/<evil>.cap");
  json a = rig::test::fixture_analysis();
  a["output_envelope"]["note"] = "<i>note</i>";
  a["dut"]["firmware"] = "<i>fw</i>";
  a["psd"]["x"]["unit"] = "g²/Hz <sup>";
  rig::test::write_run(d.path, p, &a);
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_EQ(h.find("<script"), std::string::npos);
  EXPECT_EQ(h.find("<b>bold"), std::string::npos);
  EXPECT_EQ(h.find("<img"), std::string::npos);
  EXPECT_EQ(h.find("<evil>"), std::string::npos);
  EXPECT_EQ(h.find("<i>note"), std::string::npos);
  EXPECT_EQ(h.find("<sup>"), std::string::npos);
  EXPECT_NE(h.find("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;&amp;&quot;"), std::string::npos);
  EXPECT_NE(h.find("&lt;b&gt;bold&lt;/b&gt; &amp; &quot;quoted&quot;"), std::string::npos);
  EXPECT_NE(h.find("<tr class=\"fail\">"), std::string::npos);
  EXPECT_NE(h.find("badge fail\">FAIL"), std::string::npos);
}

// A passport whose verdicts its own values and limits contradict (a FAIL edited to PASS, a
// value moved) gets no report: `rig report` printed "PASS" beside a value outside its limits
// (a review). Exit 2 naming the field; nothing written.
TEST(Report, APassportWhoseVerdictsContradictItsValuesGetsNoReport) {
  using rig::report::verdict_contradiction;
  json p = rig::test::fixture_passport();
  EXPECT_EQ(verdict_contradiction(p), "");
  json edited = p;  // FAIL turned into PASS, the value left outside
  edited["values"]["bias"]["value"] = -2e-3;
  EXPECT_EQ(verdict_contradiction(edited),
            "values.bias.outcome is PASS, but its value -0.002 is outside its limits [-0.001,0.001]");
  edited = p;  // an open lower end: the value is judged against the upper one only
  edited["values"]["in_run_b_gost_100s"]["value"] = 2e-5;
  EXPECT_NE(verdict_contradiction(edited).find("values.in_run_b_gost_100s.outcome is PASS, but its value 2e-05 is "
                                               "outside its limits [null,1e-05]"),
            std::string::npos);
  edited["values"]["in_run_b_gost_100s"]["outcome"] = "FAIL";  // the row agrees, the run does not
  EXPECT_EQ(verdict_contradiction(edited), "outcome is PASS, but values.in_run_b_gost_100s (limited) is FAIL");
  edited["outcome"] = "FAIL";
  EXPECT_EQ(verdict_contradiction(edited), "");
  edited = p;  // a limited value not measured: FAIL in a completed run, UNSET in a stopped one
  edited["values"]["bias"]["value"] = nullptr;
  EXPECT_NE(verdict_contradiction(edited).find("values.bias.outcome is PASS, but it has limits and no value"),
            std::string::npos);
  edited["values"]["bias"]["outcome"] = "UNSET";
  edited["outcome"] = "ABORTED";
  edited["aborted_reason"] = "SIGINT";
  EXPECT_EQ(verdict_contradiction(edited), "");
  edited.erase("aborted_reason");
  edited["outcome"] = "PASS";
  EXPECT_NE(verdict_contradiction(edited), "");
  // A value required without limits (accuracy_class with a class table), not measured: FAIL once
  // every phase ran, also when a signal after the last phase made the run ABORTED (a review: rig's
  // own such passport got no report); UNSET in a run that stopped before a phase ended.
  edited = p;
  edited["values"]["accuracy_class"] = {{"value", nullptr}, {"limits", nullptr}, {"outcome", "FAIL"}};
  edited["outcome"] = "FAIL";
  EXPECT_EQ(verdict_contradiction(edited), "");
  edited["outcome"] = "ABORTED";
  edited["aborted_reason"] = "aborted after the last phase: SIGINT received";
  EXPECT_EQ(verdict_contradiction(edited), "");
  edited["values"]["accuracy_class"]["outcome"] = "UNSET";  // a signal before the verdict, by an older rig
  EXPECT_EQ(verdict_contradiction(edited), "");
  edited["values"]["accuracy_class"]["outcome"] = "FAIL";
  edited["phases"].back()["status"] = "aborted";
  EXPECT_EQ(verdict_contradiction(edited),
            "values.accuracy_class.outcome is FAIL, but the run stopped early (what was not measured stays UNSET)");
  // A judged run went through every phase and lists every measurement (a review: a PASS with
  // pending phases and its failing value deleted was reported and recorded).
  edited = p;
  edited["phases"] = json::array({{{"id", "bring-up"}, {"status", "done"}}, {{"id", "loop"}, {"status", "skipped"}},
                                  {{"id", "in-run"}, {"status", "pending"}}});
  EXPECT_EQ(verdict_contradiction(edited),
            "outcome is PASS, but phases[2] (in-run) is pending (a judged run has done or skipped every phase)");
  edited["outcome"] = "FAIL";
  EXPECT_NE(verdict_contradiction(edited).find("outcome is FAIL, but phases[2] (in-run) is pending"), std::string::npos);
  edited["phases"][2]["status"] = "done";
  EXPECT_EQ(verdict_contradiction(edited), "");
  for (const std::string name : {"k", "accuracy_class"}) {
    edited = p;
    edited["values"].erase(name);
    EXPECT_EQ(verdict_contradiction(edited), "outcome is PASS, but values has no " + name +
                                                 " (a passport lists every measurement of the procedure, null when not "
                                                 "measured)");
    edited["outcome"] = "ABORTED";  // what a run that stopped early lists is not judged here
    edited["aborted_reason"] = "SIGINT";
    EXPECT_EQ(verdict_contradiction(edited), "");
  }
  edited = p;
  for (auto it = p["values"].begin(); it != p["values"].end(); ++it)
    if (it.key().rfind("in_run_b_gost_", 0) == 0) edited["values"].erase(it.key());
  EXPECT_NE(verdict_contradiction(edited).find("values has no in_run_b_gost_<N>s"), std::string::npos);
  // Nor by deleting the phases (a second review), nor by relabelling the outcome: an abort's reason
  // comes with, and only with, an ABORTED or ERROR run (a FAIL relabelled ABORTED left the yield).
  edited = p;
  edited.erase("phases");
  EXPECT_EQ(verdict_contradiction(edited), "outcome is PASS, but phases is absent (a judged run lists the phases it went through)");
  edited["phases"] = json::array();
  EXPECT_EQ(verdict_contradiction(edited), "outcome is PASS, but phases is [] (a judged run lists the phases it went through)");
  edited = p;
  edited["aborted_reason"] = "aborted: e-stop";
  EXPECT_EQ(verdict_contradiction(edited),
            "outcome is PASS, but the passport has an aborted_reason (only an ABORTED or ERROR run has one)");
  edited = p;
  edited["outcome"] = "ABORTED";
  EXPECT_EQ(verdict_contradiction(edited),
            "outcome is ABORTED, but the passport has no aborted_reason (an ABORTED or ERROR run says why it stopped)");
  // An accuracy class that is no class index, and bounds the wrong way round.
  for (const double k : {0.0, -1.0, 1.5}) {
    edited = p;
    edited["values"]["accuracy_class"]["value"] = k;
    EXPECT_NE(verdict_contradiction(edited).find("values.accuracy_class.value is "), std::string::npos) << k;
  }
  edited = p;
  std::swap(edited["values"]["in_run_b_allan"]["lo"], edited["values"]["in_run_b_allan"]["hi"]);
  EXPECT_EQ(verdict_contradiction(edited), "values.in_run_b_allan.lo 2.5e-06 is above its hi 1.8e-06");
  edited = p;  // a value moved inside its limits without its bounds
  edited["values"]["in_run_b_allan"]["value"] = 3e-6;
  EXPECT_EQ(verdict_contradiction(edited), "values.in_run_b_allan.value 3e-06 is outside its own bounds [1.8e-06, 2.5e-06]");
  edited["values"]["in_run_b_allan"]["value"] = 2.5e-6 * (1 + 1e-12);  // rounding is not an edit
  EXPECT_EQ(verdict_contradiction(edited), "");

  TempDir d;
  json bad = p;
  bad["values"]["bias"]["value"] = -2e-3;
  rig::test::write_run(d.path, bad, nullptr);
  try {
    rig::report::write_report(d.path.string());
    ADD_FAILURE() << "a report of an edited passport";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("passport.json: values.bias.outcome is PASS, but its value -0.002 is outside"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(d.path / "report.html"));
  // A unit other than the contract's (docs/contracts.md) changes what the value means: a bias edited
  // to read "mg" was reported and recorded (a technician's review). Names the contract does not
  // list keep their own.
  for (const auto& [name, unit] : std::vector<std::pair<std::string, std::string>>{
           {"bias", "mg"}, {"k", "g/s^0.5"}, {"in_run_b_gost_100s", "mg"}, {"accuracy_class", ""}}) {
    bad = p;
    bad["values"][name]["unit"] = unit;
    rig::test::write_run(d.path, bad, nullptr);
    try {
      rig::report::write_report(d.path.string());
      ADD_FAILURE() << name << " in " << unit << " reported";
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("passport.json: values." + name + ".unit: \"" + unit + "\", but " + name + " is in "),
                std::string::npos)
          << e.what();
    }
  }
  for (const bool null_unit : {true, false}) {  // absent or null: recorded as a blank unit (a re-test)
    bad = p;
    if (null_unit) bad["values"]["bias"]["unit"] = nullptr;
    else bad["values"]["bias"].erase("unit");
    rig::test::write_run(d.path, bad, nullptr);
    try {
      rig::report::write_report(d.path.string());
      ADD_FAILURE() << "a bias without its unit reported";
    } catch (const rig::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("values.bias.unit: ") + (null_unit ? "null" : "absent") +
                                           ", but bias is in g"),
                std::string::npos)
          << e.what();
    }
  }
  bad = p;
  bad["values"]["a_value_of_its_own"] = {{"value", 1.0}, {"unit", "mg"}, {"outcome", "UNSET"}};
  rig::test::write_run(d.path, bad, nullptr);
  EXPECT_NO_THROW(rig::report::write_report(d.path.string()));
}

// The passport against its run's run.json: a profile, plant, start or serial other than the run's,
// or a station on an emulated run, is a passport changed after its run (a review: an emulated ci run
// relabelled "hardware"/"paper" was reported and recorded). Without run.json nothing is compared.
TEST(Report, APassportThatIsNotItsRunsInvocationGetsNoReport) {
  const json p = rig::test::fixture_passport();
  const json run = {{"plant", "emulated"}, {"profile", "paper"}, {"serial", p["serial"]}, {"started", p["started"]}};
  auto refusal = [&](const json& passport, const json& invocation) {
    TempDir d;
    rig::test::write_run(d.path, passport, nullptr);
    rig::test::write_file(d.path / "run.json", invocation.dump());
    try {
      rig::report::write_report(d.path.string());
    } catch (const rig::ConfigError& e) {
      EXPECT_FALSE(std::filesystem::exists(d.path / "report.html"));
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(refusal(p, run), "");
  json edited = p;
  edited["plant"] = "hardware";
  EXPECT_NE(refusal(edited, run).find("passport.json: plant is \"hardware\", but the run's run.json has \"emulated\""),
            std::string::npos)
      << refusal(edited, run);
  edited = p;
  edited["profile"] = "ci";
  EXPECT_NE(refusal(edited, run).find("profile is \"ci\", but the run's run.json has \"paper\""), std::string::npos);
  edited = p;
  edited["started"] = "2026-11-20T07:00:00Z";
  EXPECT_NE(refusal(edited, run).find("started is \"2026-11-20T07:00:00Z\", but the run's run.json has"), std::string::npos);
  edited["started"] = "2026-11-20T09:00:00+01:00";  // the same instant, written another way
  EXPECT_EQ(refusal(edited, run), "");
  edited = p;
  edited["serial"] = "QA-OTHER";
  EXPECT_NE(refusal(edited, run).find("serial is \"QA-OTHER\""), std::string::npos);
  edited = p;
  edited["station"] = "line-3";
  EXPECT_NE(refusal(edited, run).find("station is \"line-3\", but the run's run.json has plant \"emulated\""),
            std::string::npos);
  json no_serial = run;  // a run given no --serial takes the DUT's: nothing to compare
  no_serial["serial"] = "";
  edited = p;
  edited["serial"] = "QA-OTHER";
  EXPECT_EQ(refusal(edited, no_serial), "");
  EXPECT_EQ(refusal(edited, json::array()), "") << "a run.json that is not an object is not compared";
}

TEST(Report, MissingAnalysisStillWritesAndSaysSo) {
  TempDir d;
  json p = rig::test::fixture_passport("QA-7", "ABORTED");
  p["aborted_reason"] = "SIGINT during phase u10u20";
  rig::test::write_run(d.path, p, nullptr);
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_NE(h.find("badge aborted\">ABORTED"), std::string::npos);
  EXPECT_NE(h.find("SIGINT during phase u10u20"), std::string::npos);
  EXPECT_NE(h.find("id=\"missing\""), std::string::npos);
  EXPECT_NE(h.find("analysis.json is missing"), std::string::npos);
  EXPECT_EQ(count(h, "data-plot="), 0u);
  EXPECT_NE(h.find("<code>bias</code>"), std::string::npos);  // the table still there
}

TEST(Report, PartialAnalysisDrawsWhatIsThereAndListsTheRest) {
  TempDir d;
  const json full = rig::test::fixture_analysis();
  const json a = {{"schema", "rig.analysis/1"}, {"runs", full["runs"]}, {"allan", {{"x", full["allan"]["x"]}}}};
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_EQ(count(h, "data-plot=\"averages\""), 1u);
  EXPECT_EQ(count(h, "data-plot=\"allan-x\""), 1u);
  EXPECT_EQ(count(h, "data-plot=\"allan-y\""), 0u);
  EXPECT_EQ(count(h, "data-plot=\"step\""), 0u);
  for (const char* what : {"allan.y", "psd.x", "psd.y", "output_envelope", "in_run", "loop.step", "loop.freq"})
    EXPECT_NE(h.find(what), std::string::npos) << what;
}

TEST(Report, MalformedAnalysisIsReportedInThePage) {
  TempDir d;
  rig::test::write_run(d.path, rig::test::fixture_passport(), nullptr);
  rig::test::write_file(d.path / "analysis.json", "{\"runs\": [1, 2,");
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_NE(h.find("analysis.json is malformed"), std::string::npos);
  EXPECT_EQ(count(h, "data-plot="), 0u);
}

// A number beyond a double's range ended `rig report` with nlohmann's "number overflow" and exit 4,
// naming no file (a review): in passport.json it is exit 2 at its line and column; in
// analysis.json the page says so and draws what it can.
TEST(Report, ANumberBeyondADoublesRangeIsNamedWhereItStands) {
  TempDir d;
  std::string text = rig::test::fixture_passport().dump(1);
  const std::size_t at = text.find("-0.00050137");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::string("-0.00050137").size(), "1e400");
  const std::size_t line = static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n')) + 1;
  rig::test::write_file(d.path / "passport.json", text);
  try {
    rig::report::write_report(d.path.string());
    ADD_FAILURE() << "a report of a passport with 1e400";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("passport.json:" + std::to_string(line) + ":"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(": the number 1e400 is beyond the range of a double"), std::string::npos)
        << e.what();
  }
  rig::test::write_run(d.path, rig::test::fixture_passport(), nullptr);
  rig::test::write_file(d.path / "analysis.json", "{\"schema\": \"rig.analysis/1\",\n \"device_time_s\": 1e999}");
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_NE(h.find("analysis.json is malformed: 2:19: the number 1e999 is beyond the range of a double"), std::string::npos);
}

// A colleague's copy of a run folder: the page names the folder it was made from, and where the
// run wrote it (the footer named the original folder, which the history did not, a review).
TEST(Report, ACopiedFolderNamesTheFolderReadAndWhereTheRunWroteIt) {
  TempDir d;
  json p = rig::test::fixture_passport();
  p["out_dir"] = "/line2/runs/QA-0042";
  rig::test::write_run(d.path / "copy", p, nullptr);
  const std::string h = slurp(rig::report::write_report((d.path / "copy/").string()));
  const std::string read = std::filesystem::weakly_canonical(d.path / "copy").string();
  EXPECT_NE(h.find("Run folder</dt><dd class=\"wrap\">" + read + "</dd>"), std::string::npos);
  EXPECT_NE(h.find("Written at</dt><dd class=\"wrap\">/line2/runs/QA-0042</dd>"), std::string::npos);
  EXPECT_NE(h.find("from passport.json in " + read + "."), std::string::npos);
  // The run's own folder: one row, as before (a sealed folder's report stays byte for byte).
  p["out_dir"] = read;
  rig::test::write_run(d.path / "copy", p, nullptr);
  const std::string own = slurp(rig::report::write_report((d.path / "copy").string()));
  EXPECT_EQ(own.find("Written at"), std::string::npos);
  EXPECT_NE(own.find("Run folder</dt><dd class=\"wrap\">" + read + "</dd>"), std::string::npos);
}

// The GOST B rows stand where the contract puts them (after base_error) whatever their block
// lengths: the ci profile's in_run_b_gost_2s and _4s were printed last (a review).
TEST(Report, GostRowsFollowTheBaseErrorWhateverTheirBlockLength) {
  json p = rig::test::fixture_passport();
  json values = json::object();
  for (auto& [name, v] : p["values"].items())
    if (name.rfind("in_run_b_gost_", 0) != 0) values[name] = v;
  values["in_run_b_gost_2s"] = p["values"]["in_run_b_gost_100s"];
  values["in_run_b_gost_4s"] = p["values"]["in_run_b_gost_200s"];
  p["values"] = values;  // an object: its keys sorted, so the GOST rows come after accuracy_class here
  const std::string h = rig::report::render_report(p, json());
  const auto at = [&](const std::string& name) { return h.find("<code>" + name + "</code>"); };
  EXPECT_LT(at("base_error"), at("in_run_b_gost_2s"));
  EXPECT_LT(at("in_run_b_gost_2s"), at("in_run_b_gost_4s"));
  EXPECT_LT(at("in_run_b_gost_4s"), at("in_run_b_allan"));
  EXPECT_NE(h.find("In-run B, (max − min)/2 of 4 s averages (GOST)"), std::string::npos);
}

// What an interrupted attempt left (*.interrupted-N) is listed as set aside: a reader found
// captures/in-run-U10.cap.interrupted-1 in a resumed run's folder and nowhere in its report (a
// review). The passport's captures stay what the run recorded.
TEST(Report, FilesAnInterruptedAttemptLeftAreListedAsSetAside) {
  TempDir d;
  rig::test::write_run(d.path, rig::test::fixture_passport(), nullptr);
  std::filesystem::create_directories(d.path / "captures");
  rig::test::write_file(d.path / "captures" / "in-run-U10.cap.interrupted-1", "x");
  rig::test::write_file(d.path / "loop-test.csv.interrupted-2", "x");
  rig::test::write_file(d.path / "captures" / "in-run-U10.cap", "x");
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  const std::size_t list = h.find("<ul id=\"set-aside\">");
  ASSERT_NE(list, std::string::npos);
  EXPECT_NE(h.find("<li><code>captures/in-run-U10.cap.interrupted-1</code></li>", list), std::string::npos);
  EXPECT_NE(h.find("<li><code>loop-test.csv.interrupted-2</code></li>", list), std::string::npos);
  EXPECT_EQ(h.find("<li><code>captures/in-run-U10.cap</code></li>", list), std::string::npos);
  // Rendered from memory (no folder): nothing to list.
  EXPECT_EQ(rig::report::render_report(rig::test::fixture_passport(), json()).find("set-aside"), std::string::npos);
}

TEST(Report, AnalysisWithWrongTypesDoesNotCrash) {
  TempDir d;
  const json a = {{"runs", "oops"},
                  {"allan", {{"x", {{"oadev", {{{"tau_s", "1"}, {"dev", nullptr}}}}}}}},
                  {"psd", {{"x", {{"f_hz", {1, 2}}, {"psd", {-1, 0}}}}}},
                  {"timeseries", {{"rate_hz", 0}}},
                  {"output_envelope", {{"t_s", "x"}, {"block_s", "2"}}},
                  {"in_run", {{"blocks", 7}}},
                  {"dut", {{"firmware", 3}, {"temperature_c", "hot"}}},
                  {"device_time_s", "long"},
                  {"loop", {{"step", 3}, {"freq", {{"f_hz", nullptr}}}}}};
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_NE(h.find("analysis.json output_envelope"), std::string::npos);
  EXPECT_NE(h.find("no data"), std::string::npos);  // plots with nothing drawable say so
}

TEST(Report, MissingPassportNamesTheFile) {
  TempDir d;
  try {
    rig::report::write_report((d.path / "nope").string());
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("nope/passport.json"), std::string::npos) << e.what();
  }
}

TEST(Report, MalformedPassportNamesFileAndLine) {
  TempDir d;
  rig::test::write_file(d.path / "passport.json", "{\n  \"serial\": \"A\",\n  \"values\": {,\n}");
  try {
    rig::report::write_report(d.path.string());
    FAIL() << "no exception";
  } catch (const rig::ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("passport.json"), std::string::npos) << w;
    EXPECT_NE(w.find("line 3"), std::string::npos) << w;
  }
  rig::test::write_file(d.path / "passport.json", R"({"schema": "rig.passport/9", "serial": "A"})");
  EXPECT_THROW(rig::report::write_report(d.path.string()), rig::ConfigError);
  rig::test::write_file(d.path / "passport.json", R"([1, 2])");
  EXPECT_THROW(rig::report::write_report(d.path.string()), rig::ConfigError);
  EXPECT_FALSE(std::filesystem::exists(d.path / "report.html"));
}

TEST(ReportCli, WritesTheReportAndRejectsAFolderWithoutPassport) {
  TempDir d;
  const json a = rig::test::fixture_analysis();
  rig::test::write_run(d.path / "run", rig::test::fixture_passport(), &a);
  {
    CLI::App app;
    int rc = -1;
    rig::cli::add_report(app, rc);
    const std::string dir = (d.path / "run").string();
    std::vector<std::string> args{dir, "report"};  // CLI11 parses a reversed vector
    testing::internal::CaptureStdout();
    app.parse(args);
    testing::internal::GetCapturedStdout();
    EXPECT_EQ(rc, rig::kExitPass);
    EXPECT_TRUE(std::filesystem::exists(d.path / "run" / "report.html"));
  }
  CLI::App app;
  int rc = -1;
  rig::cli::add_report(app, rc);
  std::vector<std::string> args{(d.path / "empty").string(), "report"};
  EXPECT_THROW(app.parse(args), rig::ConfigError);  // main() maps this to exit 2
  // The passport file itself given for the folder (it said ".../passport.json/passport.json:
  // cannot read the file (does the run folder exist?)").
  try {
    rig::report::read_passport((d.path / "run" / "passport.json").string());
    ADD_FAILURE() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              (d.path / "run" / "passport.json").string() + ": a file, not a run folder (give the folder that holds passport.json)");
  }
  // A folder that is there but holds no run is named so (it asked "does the run folder exist?").
  std::filesystem::create_directories(d.path / "no-run");
  try {
    rig::report::read_passport((d.path / "no-run").string());
    ADD_FAILURE() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), (d.path / "no-run" / "passport.json").string() + ": not there: " +
                                         (d.path / "no-run").string() + " is a folder but not a run folder (no passport.json)");
  }
  // One with run.json is a run stopped before its end (killed): to resume, not "not a run folder".
  std::ofstream(d.path / "no-run" / "run.json") << "{}";
  try {
    rig::report::read_passport((d.path / "no-run").string());
    ADD_FAILURE() << "no exception";
  } catch (const rig::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), (d.path / "no-run" / "passport.json").string() + ": not there: the run in " +
                                         (d.path / "no-run").string() + " has not finished (run.json, no passport: "
                                         "still running, or stopped before its end); `rig run --resume " +
                                         (d.path / "no-run").string() + "` finishes a stopped one");
  }
}

// ---------------------------------------------------------------- the SVG writer
TEST(Svg, LogAxesGetDecadeTicksAndOneToTwoFivePadding) {
  rig::report::Plot p;
  p.id = "t";
  p.log_x = p.log_y = true;
  p.series.push_back({"s", {0.003, 900}, {2e-6, 3e-3}, {}, {}});
  const std::string s = rig::report::to_svg(p);
  // x: 0.003..900 -> 2e-3..1e3: decades 10^-2..10^3 labelled, not 10^-3 or 10^4.
  for (int e : {-2, 0, 3}) EXPECT_NE(s.find(">10<tspan dy=\"-6\" font-size=\"9\">" + std::to_string(e) + "<"), std::string::npos) << e;
  EXPECT_EQ(s.find("font-size=\"9\">4<"), std::string::npos);
  EXPECT_EQ(s.find("font-size=\"9\">-7<"), std::string::npos);
  // y: 2e-6..3e-3 -> 2e-6..5e-3: 10^-5..10^-3 labelled, 10^-6 lies outside.
  EXPECT_NE(s.find("font-size=\"9\">-5<"), std::string::npos);
  EXPECT_EQ(s.find("font-size=\"9\">-6<"), std::string::npos);
}

TEST(Svg, LinearTickLabelsAreExact) {
  rig::report::Plot p;
  p.id = "l";
  p.series.push_back({"s", {0, 1}, {0, 0.014}, {}, {}});  // step 0.0025
  const std::string s = rig::report::to_svg(p);
  EXPECT_NE(s.find(">0.0025<"), std::string::npos);
  EXPECT_NE(s.find(">0.0125<"), std::string::npos);
  EXPECT_EQ(s.find(">0.003<"), std::string::npos);  // not rounded to 3 decimals
}

TEST(Svg, LongSeriesIsDecimatedAndNaNBreaksTheLine) {
  rig::report::Plot p;
  p.id = "d";
  rig::report::Series s;
  for (int i = 0; i < 200000; ++i) {
    s.x.push_back(i);
    s.y.push_back(i == 100000 ? std::nan("") : std::sin(i * 0.01));
  }
  p.series.push_back(s);
  const std::string svg = rig::report::to_svg(p);
  EXPECT_EQ(count(svg, "<polyline"), 2u);           // split at the NaN
  EXPECT_LT(count(svg, ","), 4u * 2u * 900u);       // at most ~2 points per pixel column
  EXPECT_GT(count(svg, ","), 800u);                 // but still every column
}

TEST(Svg, DenseMarkersAreThinnedToOnePerTwoPixels) {
  rig::report::Plot p;
  p.id = "m";
  p.log_x = true;
  rig::report::Series s;
  s.style = rig::report::Series::Style::markers;
  for (int i = 1; i <= 20000; ++i) {
    s.x.push_back(i * 1e-3);
    s.y.push_back(1.0 / i);
  }
  p.series.push_back(s);
  const std::size_t circles = count(rig::report::to_svg(p), "<circle");
  EXPECT_LE(circles, 410u);  // 804 px wide plot area / 2 px
  EXPECT_GE(circles, 100u);
}

TEST(Svg, CloseMarkerLabelsDoNotOverlap) {
  rig::report::Plot p;
  p.id = "k";
  p.series.push_back({"s", {0, 100}, {0, 1}, {}, {}});
  for (double f : {50.0, 50.5, 51.0, 51.5, 52.0, 52.5})  // six peaks within a few pixels, near the top
    p.markers.push_back({f, 0.97, "peak " + rig::report::fmt_num(f), "#d62728"});
  const std::string svg = rig::report::to_svg(p);
  struct Box { double x0, y0, x1, y1; };
  std::vector<Box> boxes;
  auto attr = [&](std::size_t tag, const char* name) {
    const std::size_t at = svg.find(std::string(" ") + name + "=\"", tag);
    return std::stod(svg.substr(at + std::strlen(name) + 3));
  };
  for (std::size_t at = svg.find("class=\"mark\""); at != std::string::npos; at = svg.find("class=\"mark\"", at + 1)) {
    const std::size_t tag = svg.rfind("<text", at);
    const double x = attr(tag, "x"), y = attr(tag, "y");
    const std::size_t t0 = svg.find('>', at) + 1;
    const double w = 7.0 * static_cast<double>(svg.find('<', t0) - t0);
    const bool end = svg.substr(tag, t0 - tag).find("text-anchor=\"end\"") != std::string::npos;
    boxes.push_back({end ? x - w : x, y - 12, end ? x : x + w, y});
  }
  ASSERT_EQ(boxes.size(), 6u);  // all placed
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j) {
      const Box& a = boxes[i];
      const Box& b = boxes[j];
      EXPECT_FALSE(a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1) << i << " overlaps " << j;
    }
}

TEST(Svg, EmptyPlotSaysNoDataAndEscapesTitles) {
  rig::report::Plot p;
  p.id = "e\"";
  p.title = "<t>";
  p.log_y = true;
  p.series.push_back({"neg", {1, 2}, {-1, 0}, {}, {}});  // nothing drawable on a log axis
  const std::string s = rig::report::to_svg(p);
  EXPECT_NE(s.find(">no data<"), std::string::npos);
  EXPECT_NE(s.find("&lt;t&gt;"), std::string::npos);
  EXPECT_EQ(s.find("<t>"), std::string::npos);
  EXPECT_NE(s.find("data-plot=\"e&quot;\""), std::string::npos);
}

TEST(Svg, NumbersForPeople) {
  EXPECT_EQ(rig::report::fmt_num(2.1e-6, 3), "2.1e-06");
  EXPECT_EQ(rig::report::fmt_num(492, 4), "492");
  EXPECT_EQ(rig::report::fmt_num(std::nan(""), 4), "—");
  EXPECT_EQ(rig::report::html_escape("a<&>\"'"), "a&lt;&amp;&gt;&quot;&#39;");
}

}  // namespace
