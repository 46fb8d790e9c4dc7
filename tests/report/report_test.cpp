// report.html from a generated run folder: content, escaping, partial and missing inputs,
// and the SVG writer's axes and decimation. The browser check is in browser_test.cpp.
#include <gtest/gtest.h>

#include <cstring>


#include "app/commands.hpp"
#include "rig/core/errors.hpp"
#include "rig/report/report.hpp"
#include "rig/report/svg.hpp"
#include "tests/report/fixture.hpp"

namespace {

using nlohmann::json;
using rig::test::TempDir;

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t count(const std::string& hay, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + 1)) ++n;
  return n;
}

const char* const kPlots[] = {"allan-x", "allan-y", "psd-x", "psd-y", "timeseries", "averages", "in-run", "step", "freq"};

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
  EXPECT_NE(h.find("1.8e-06 … 2.5e-06"), std::string::npos);         // bounds
  EXPECT_NE(h.find("[−∞, 5e-06]"), std::string::npos);               // one-sided limit
  EXPECT_NE(h.find("needs a record longer than 50 h"), std::string::npos);  // r's reason
  // Contract order: bias before base_error before accuracy_class (not alphabetical).
  EXPECT_LT(h.find("<code>bias</code>"), h.find("<code>base_error</code>"));
  EXPECT_LT(h.find("<code>settling_time</code>"), h.find("<code>accuracy_class</code>"));
  for (const char* id : kPlots) EXPECT_EQ(count(h, "data-plot=\"" + std::string(id) + "\""), 1u) << id;
  EXPECT_NE(h.find("τ_ср = 200 s"), std::string::npos);
  EXPECT_NE(h.find(">72 Hz<"), std::string::npos);     // labelled PSD peak
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
  EXPECT_NE(e.find("<dt>Stopped because</dt><dd>DUT link lost</dd>"), std::string::npos);
}

TEST(Report, EscapesEveryTextFromTheRunFolder) {
  TempDir d;
  json p = rig::test::fixture_passport("<script>alert('x')</script>&\"", "FAIL");
  p["values"]["bias"]["reason"] = "<b>bold</b> & \"quoted\"";
  p["values"]["bias"]["outcome"] = "FAIL";
  p["values"]["<img src=x>"] = {{"value", 1}, {"unit", "<u>"}, {"outcome", "PASS"}};
  p["phases"][0]["message"] = "</td><script>";
  p["captures"].push_back("captures/<evil>.cap");
  json a = rig::test::fixture_analysis();
  a["timeseries"]["note"] = "<i>note</i>";
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
  for (const char* what : {"allan.y", "psd.x", "psd.y", "timeseries", "in_run", "loop.step", "loop.freq"})
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

TEST(Report, AnalysisWithWrongTypesDoesNotCrash) {
  TempDir d;
  const json a = {{"runs", "oops"},
                  {"allan", {{"x", {{"oadev", {{{"tau_s", "1"}, {"dev", nullptr}}}}}}}},
                  {"psd", {{"x", {{"f_hz", {1, 2}}, {"psd", {-1, 0}}}}}},
                  {"timeseries", {{"rate_hz", 0}}},
                  {"loop", {{"step", 3}, {"freq", {{"f_hz", nullptr}}}}}};
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  const std::string h = slurp(rig::report::write_report(d.path.string()));
  EXPECT_NE(h.find("timeseries.rate_hz"), std::string::npos);
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
