// A real `rig run --profile ci` on the emulated plant, then its analysis.json and report.html:
// the data the printed passport needs come from the procedure (the whole raw capture as block
// envelopes, the fitted curves, the DUT's firmware and temperature, the device time, the
// bounds' level), and the page labels the ci profile's GOST rows with their real 2 s and 4 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tests/report/fixture.hpp"

namespace {

using nlohmann::json;

using rig::test::slurp;

TEST(RunReport, CiRunCarriesWhatThePrintedPassportShows) {
  rig::test::TempDir d;
  const std::string cmd = std::string(RIG_BINARY) + " run --plant emulated --profile ci --yes --quiet --no-history --out " +
                          (d.path / "run").string() + " > " + (d.path / "out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(d.path / "out.txt");
  const json a = json::parse(slurp(d.path / "run" / "analysis.json"));

  // The whole 60 s raw capture, about 1000 blocks, means inside each block's raw extremes.
  const json& env = a.at("output_envelope");
  const double block = env.at("block_s").get<double>();
  ASSERT_EQ(env["t_s"].size(), env["x"]["mean"].size());
  EXPECT_NEAR(block, 0.06, 1e-12);
  EXPECT_EQ(env["t_s"].size(), 1000u);
  EXPECT_NEAR(env["t_s"].back().get<double>(), 60 - block / 2, 1e-9);
  for (const char* ch : {"x", "y"})
    for (std::size_t i = 0; i < env["t_s"].size(); ++i) {
      const double lo = env[ch]["min"][i], m = env[ch]["mean"][i], hi = env[ch]["max"][i];
      ASSERT_LE(lo, m) << ch << i;
      ASSERT_LE(m, hi) << ch << i;
    }

  // The fitted curves on the Allan taus: N's is N / sqrt(tau) (IEEE 952), in the seconds basis.
  const json& nt = a["allan"]["x"]["noise_terms"];
  const double n = nt["N"]["value"].get<double>();
  ASSERT_EQ(nt["curves"]["N"].size(), a["allan"]["x"]["oadev"].size());
  for (std::size_t i = 0; i < nt["curves"]["N"].size(); ++i) {
    const double tau = a["allan"]["x"]["oadev"][i]["tau_s"];
    EXPECT_NEAR(nt["curves"]["N"][i].get<double>(), n / std::sqrt(tau), 1e-12 * n / std::sqrt(tau));
  }
  // The passport's n is the same number as analysis.json's per-hour view of N, bit for bit.
  const json p = json::parse(slurp(d.path / "run" / "passport.json"));
  EXPECT_EQ(p["values"]["n"]["value"].get<double>(), nt["N"]["per_hour"]["value"].get<double>());
  EXPECT_EQ(p["values"]["n"]["unit"], nt["N"]["per_hour"]["unit"]);

  // A null term's reason states its upper limit in the passport value's own unit (per hour), the
  // number analysis.json's per_hour.hi holds; analysis.json's reason keeps it per second.
  int limits_checked = 0;
  for (const auto& [name, sym] : {std::pair{"q", "Q"}, {"n", "N"}, {"k", "K"}, {"r", "R"}}) {
    const json& v = p["values"][name];
    const json& ph = nt[sym]["per_hour"];
    if (!v["value"].is_null() || !ph.contains("hi")) continue;
    ++limits_checked;
    char limit[64];
    std::snprintf(limit, sizeof limit, "upper limit %s <= %.3g %s", sym, ph["hi"].get<double>(),
                  v["unit"].get<std::string>().c_str());
    const std::string why = v["reason"];
    EXPECT_NE(why.find(limit), std::string::npos) << name << ": " << why << " (wanted \"" << limit << "\")";
    EXPECT_EQ(why.find("/s"), std::string::npos) << name << ": " << why;
    EXPECT_NE(nt[sym]["reason"].get<std::string>().find(" " + nt[sym]["unit"].get<std::string>()), std::string::npos);
  }
  EXPECT_GE(limits_checked, 2);  // the ci run's K and R: null with an upper limit (seeded plant)

  EXPECT_DOUBLE_EQ(a["allan"]["confidence"].get<double>(), 0.6826894921370859);
  EXPECT_FALSE(a["dut"]["firmware"].get<std::string>().empty());
  EXPECT_TRUE(a["dut"]["temperature_c"].is_number());
  // Device time: at least the recorded 12 x 2 s + 40 s + 60 s, plus moves and settling.
  EXPECT_GT(a["device_time_s"].get<double>(), 124.0);

  const std::string h = slurp(d.path / "run" / "report.html");
  EXPECT_NE(h.find("In-run B, (max − min)/2 of 2 s block means (GOST)"), std::string::npos);
  EXPECT_NE(h.find("In-run B, (max − min)/2 of 4 s block means (GOST)"), std::string::npos);
  EXPECT_EQ(h.find("100 s averages"), std::string::npos);
  EXPECT_EQ(h.find("100 s block"), std::string::npos);
  EXPECT_NE(h.find("2 s averages of the U10 and U20 runs"), std::string::npos);
  EXPECT_NE(h.find("<dt>Device time</dt>"), std::string::npos);
  EXPECT_EQ(h.find("id=\"missing\""), std::string::npos);  // every plot drawn

  // `rig run` renders the page from the analysis document it holds, not from the file it wrote;
  // `rig report` reads the file: the same page, byte for byte (doubles survive the JSON round trip).
  const std::string rep = std::string(RIG_BINARY) + " report " + (d.path / "run").string() + " > " +
                          (d.path / "report-out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(rep.c_str()), 0) << slurp(d.path / "report-out.txt");
  EXPECT_TRUE(slurp(d.path / "run" / "report.html") == h) << "rig report drew another page than rig run";
}

}  // namespace
