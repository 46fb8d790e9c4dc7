// report.html in a real browser (Debian's chromium, headless; label `browser`): it loads
// with no console messages, every plot is in the rendered DOM with drawn content, and it
// prints to A4 pages. The console check is itself checked on a page with a script error.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <sstream>
#include <thread>

#include "rig/report/report.hpp"
#include "tests/report/fixture.hpp"

namespace {

using nlohmann::json;
using rig::test::TempDir;

std::string chromium_path() {
  if (const char* e = std::getenv("RIG_CHROMIUM"); e && *e) return e;
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
    if (access(p, X_OK) == 0) return p;
  return "";
}

using rig::test::slurp;

struct Browser {
  std::string out, err;  // stdout (the DOM with --dump-dom) and stderr (the log)
  int status = -1;
};

// Runs headless chromium on `page` with `mode` (--dump-dom, --print-to-pdf=...), its own
// profile folder and no network services; killed if it has not finished within 90 s.
Browser run_chromium(const std::filesystem::path& page, const std::string& mode) {
  TempDir work;
  const std::string profile = (work.path / "profile").string(), o = (work.path / "out").string(),
                    e = (work.path / "err").string();
  std::vector<std::string> argv = {chromium_path(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                                   "--no-first-run", "--disable-background-networking", "--disable-component-update",
                                   "--disable-sync", "--user-data-dir=" + profile, "--enable-logging=stderr", "--v=0",
                                   "--no-pdf-header-footer", mode, "file://" + page.string()};
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);  // its own group, so a timeout can end chromium's helper processes too
    const int fo = open(o.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), fe = open(e.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fo, 1);
    dup2(fe, 2);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  Browser b;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(90);
  int st = 0;
  while (waitpid(pid, &st, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(-pid, SIGKILL);
      waitpid(pid, &st, 0);
      b.err = "timed out\n";
      return b;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  b.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  b.out = slurp(o);
  b.err = slurp(e);
  return b;
}

// Lines the page's console produced (console.*, uncaught exceptions, failed loads).
std::vector<std::string> console_lines(const std::string& log) {
  std::vector<std::string> out;
  std::istringstream in(log);
  for (std::string l; std::getline(in, l);)
    if (l.find(":CONSOLE") != std::string::npos || l.find("Uncaught") != std::string::npos) out.push_back(l);
  return out;
}

class ReportBrowser : public ::testing::Test {
 protected:
  void SetUp() override {
    if (chromium_path().empty()) GTEST_SKIP() << "chromium is not installed (Debian package chromium)";
  }
};

TEST_F(ReportBrowser, ConsoleCheckSeesAScriptError) {  // the check below can fail
  TempDir d;
  rig::test::write_file(d.path / "bad.html",
                        "<!DOCTYPE html><html><body><p>x</p><script>no_such_function();</script></body></html>");
  const Browser b = run_chromium(d.path / "bad.html", "--dump-dom");
  ASSERT_EQ(b.status, 0) << b.err;
  const auto lines = console_lines(b.err);
  ASSERT_FALSE(lines.empty()) << b.err;
  EXPECT_NE(lines[0].find("no_such_function"), std::string::npos);
}

TEST_F(ReportBrowser, FullReportLoadsCleanWithEveryPlotDrawn) {
  TempDir d;
  const json a = rig::test::fixture_analysis();
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  const std::string page = rig::report::write_report(d.path.string());
  const Browser b = run_chromium(page, "--dump-dom");
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_TRUE(console_lines(b.err).empty()) << b.err;
  // Every plot is in the DOM the browser built, and has drawn marks.
  // (plain search: libstdc++'s std::regex recurses per character and overflows on 100 kB of SVG)
  std::vector<std::string> ids;
  for (std::size_t at = b.out.find("<svg"); at != std::string::npos; at = b.out.find("<svg", at + 1)) {
    const std::size_t end = b.out.find("</svg>", at);
    ASSERT_NE(end, std::string::npos);
    const std::string body = b.out.substr(at, end - at);
    const std::size_t id = body.find("data-plot=\"");
    ASSERT_NE(id, std::string::npos);
    ids.push_back(body.substr(id + 11, body.find('"', id + 11) - id - 11));
    EXPECT_TRUE(body.find("<polyline") != std::string::npos || body.find("<circle") != std::string::npos) << ids.back();
    EXPECT_EQ(body.find("no data"), std::string::npos) << ids.back();
  }
  EXPECT_EQ(ids, (std::vector<std::string>{"allan-x", "allan-y", "psd-x", "psd-y", "timeseries", "timeseries-range",
                                           "averages", "in-run", "step", "freq"}));
  EXPECT_NE(b.out.find("QA-0042"), std::string::npos);
  EXPECT_NE(b.out.find("<table id=\"passport\">"), std::string::npos);
}

// The printed passport's content as the browser built it: the sign-off block, each bounds
// cell's interval level, the GOST rows' block lengths, DUT firmware and temperature, device
// time, per-hour units only, PSD captions naming the labelled peaks, the step axis scaled.
TEST_F(ReportBrowser, RenderedPassportCarriesWhatAMetrologistReads) {
  TempDir d;
  json a = rig::test::fixture_analysis();
  a["in_run"]["blocks"][0]["block_s"] = 2.0;  // the ci profile's blocks under the ..._100s name
  json p = rig::test::fixture_passport();
  p["values"]["bias"]["lo"] = -5.1e-4;
  p["values"]["bias"]["hi"] = -4.9e-4;
  rig::test::write_run(d.path, p, &a);
  const Browser b = run_chromium(rig::report::write_report(d.path.string()), "--dump-dom");
  ASSERT_EQ(b.status, 0) << b.err;
  const std::string& dom = b.out;
  const std::size_t sig = dom.find("id=\"signatures\"");
  ASSERT_NE(sig, std::string::npos);
  for (const char* cell : {">Tested by<", ">Checked by<", ">Signature<", ">Date<"})
    EXPECT_NE(dom.find(cell, sig), std::string::npos) << cell;
  EXPECT_NE(dom.find("<div class=\"lvl\">95 %, GOST R 8.736</div>"), std::string::npos);
  EXPECT_NE(dom.find("<div class=\"lvl\">68 %, ±1 σ of the Allan fit</div>"), std::string::npos);  // in_run_b_allan
  EXPECT_NE(dom.find("(max − min)/2 of 2 s block means"), std::string::npos);
  EXPECT_NE(dom.find("<dd>1.4.0</dd>"), std::string::npos);
  EXPECT_NE(dom.find("<dd>22.5 °C (at bring-up)</dd>"), std::string::npos);
  EXPECT_NE(dom.find("<dt>Device time</dt>"), std::string::npos);
  EXPECT_EQ(dom.find("g*s"), std::string::npos);
  // Each PSD caption names the peaks its plot labels.
  for (const char* id : {"psd-x", "psd-y"}) {
    const std::size_t at = dom.find(std::string("data-plot=\"") + id + "\"");
    ASSERT_NE(at, std::string::npos) << id;
    const std::string svg = dom.substr(at, dom.find("</svg>", at) - at);
    std::vector<std::pair<double, std::string>> marks;
    for (std::size_t m = svg.find("class=\"mark\""); m != std::string::npos; m = svg.find("class=\"mark\"", m + 1)) {
      const std::size_t t0 = svg.find('>', m) + 1;
      const std::string label = svg.substr(t0, svg.find('<', t0) - t0);
      marks.emplace_back(std::stod(label), label);
    }
    std::sort(marks.begin(), marks.end());
    std::string joined;
    for (const auto& [f, label] : marks) joined += (joined.empty() ? "" : ", ") + label;
    const std::size_t cap = dom.find("<figcaption", at);
    EXPECT_NE(dom.substr(cap, dom.find("</figcaption>", cap) - cap).find("labelled peaks: " + joined + "."),
              std::string::npos)
        << id << ": " << joined;
  }
  // The 10 ms step record drawn over three settling times (3 ms each): ticks end below 0.01 s.
  const std::size_t step = dom.find("data-plot=\"step\"");
  ASSERT_NE(step, std::string::npos);
  const std::string svg = dom.substr(step, dom.find("</svg>", step) - step);
  EXPECT_NE(svg.find(">0.008<"), std::string::npos);
  EXPECT_EQ(svg.find(">0.01<"), std::string::npos);
}

TEST_F(ReportBrowser, AbortedRunWithoutAnalysisLoadsClean) {
  TempDir d;
  json p = rig::test::fixture_passport("QA-9", "ABORTED");
  p["aborted_reason"] = "SIGTERM";
  rig::test::write_run(d.path, p, nullptr);
  const Browser b = run_chromium(rig::report::write_report(d.path.string()), "--dump-dom");
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_TRUE(console_lines(b.err).empty()) << b.err;
  EXPECT_NE(b.out.find("id=\"missing\""), std::string::npos);
  EXPECT_NE(b.out.find("analysis.json is missing"), std::string::npos);
}

TEST_F(ReportBrowser, PrintsOnA4Pages) {
  TempDir d;
  const json a = rig::test::fixture_analysis();
  rig::test::write_run(d.path, rig::test::fixture_passport(), &a);
  const std::string page = rig::report::write_report(d.path.string());
  const std::string pdf = (d.path / "report.pdf").string();
  const Browser b = run_chromium(page, "--print-to-pdf=" + pdf);
  ASSERT_EQ(b.status, 0) << b.err;
  const std::string doc = slurp(pdf);
  ASSERT_EQ(doc.rfind("%PDF-", 0), 0u);
  // Every page A4 (595 x 842 pt, Chromium writes 594.96 x 841.92) from the @page rule.
  int pages = 0;
  const std::string key = "/MediaBox [0 0 ";
  for (std::size_t at = doc.find(key); at != std::string::npos; at = doc.find(key, at + 1), ++pages) {
    std::istringstream box(doc.substr(at + key.size(), 40));
    double w = 0, hgt = 0;
    box >> w >> hgt;
    EXPECT_NEAR(w, 595.0, 1.5);
    EXPECT_NEAR(hgt, 842.0, 1.5);
  }
  // Identity + table, then one page per group of plots (page breaks before each group).
  EXPECT_GE(pages, 5);
  EXPECT_LE(pages, 12);
}

}  // namespace
