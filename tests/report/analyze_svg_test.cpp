// `rig analyze --svg` and report.html draw with one plotter (rig/report/svg_plot.hpp): the
// standalone files carry the report's plot structure and styles, the fitted-term legend in the
// passport's per-hour units, and every text escaped (quotes included).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <utility>

#include "app/commands.hpp"
#include "rig/core/errors.hpp"
#include "tests/report/fixture.hpp"

namespace {

using rig::test::slurp;

// Writes 40000 values at 1 kHz: white noise of 1e-3 plus a line of amplitude `tone` at `tone_hz`.
void write_record(const std::filesystem::path& file, unsigned seed, double tone = 0, double tone_hz = 0) {
  std::ofstream o(file);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1e-3);
  const double pi = 3.141592653589793;
  for (int i = 0; i < 40000; ++i) o << g(rng) + tone * std::sin(2 * pi * tone_hz * i / 1000.0) << "\n";
}

// `rig analyze ARGS...` in process: its exit code and its standard output.
std::pair<int, std::string> analyze(std::vector<std::string> args) {
  CLI::App app;
  int rc = -1;
  rig::cli::add_analyze(app, rc);
  args.insert(args.begin(), "analyze");
  std::reverse(args.begin(), args.end());  // CLI11 parses a reversed vector
  testing::internal::CaptureStdout();
  app.parse(args);
  return {rc, testing::internal::GetCapturedStdout()};
}

TEST(AnalyzeSvg, DrawsWithTheReportsPlotterAndEscapesTheFileName) {
  rig::test::TempDir d;
  // White noise at 1 kHz: N is identified; the file name holds characters to escape.
  const std::filesystem::path data = d.path / "a\"b<c>&'.txt";
  write_record(data, 3);
  ASSERT_EQ(analyze({data.string(), "--svg", (d.path / "svg").string()}).first, rig::kExitPass);
  const std::string allan = slurp(d.path / "svg" / "allan.svg"), psd = slurp(d.path / "svg" / "psd.svg");
  for (const std::string* s : {&allan, &psd}) {
    EXPECT_EQ(s->rfind("<?xml", 0), 0u);
    EXPECT_NE(s->find("<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\""), std::string::npos);
    EXPECT_NE(s->find("<style>"), std::string::npos);  // standalone: styles inside
    EXPECT_NE(s->find("a&quot;b&lt;c&gt;&amp;&#39;.txt"), std::string::npos);
    EXPECT_EQ(s->find("a\"b"), std::string::npos);
    EXPECT_EQ(s->find("<c>"), std::string::npos);
  }
  EXPECT_NE(allan.find("data-plot=\"allan\""), std::string::npos);
  EXPECT_NE(allan.find("OADEV with 68.3 % bounds"), std::string::npos);
  EXPECT_NE(allan.find("N = "), std::string::npos);
  EXPECT_NE(allan.find(" g*h^0.5"), std::string::npos);  // the per-hour unit, as in the passport
  EXPECT_EQ(allan.find("g*s"), std::string::npos);
  EXPECT_NE(psd.find("data-plot=\"psd\""), std::string::npos);
  EXPECT_NE(psd.find("<polyline"), std::string::npos);
}

// The terminal summary names each PSD peak with its alias, as the plots do (docs/analysis.md,
// "PSD peaks and aliases"): a 250 Hz line sampled at 1 kHz is "250 Hz or 750 Hz".
TEST(AnalyzeSvg, TerminalSummaryNamesEachPeakWithItsAlias) {
  rig::test::TempDir d;
  const std::filesystem::path data = d.path / "tone.txt";
  write_record(data, 5, 1e-2, 250.0);
  const auto [rc, out] = analyze({data.string(), "--rate", "1000"});
  ASSERT_EQ(rc, rig::kExitPass);
  const auto line = out.find("psd: welch");
  ASSERT_NE(line, std::string::npos) << out;
  const std::string peaks = out.substr(line, out.find('\n', line) - line);
  EXPECT_NE(peaks.find("peaks: 250 Hz or 750 Hz"), std::string::npos) << peaks;
}

}  // namespace
