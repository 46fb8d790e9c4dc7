// The calibration table (docs/plant.md) for the default profile: the shipped acceptance
// procedure -- `rig run --plant emulated` on the paper profile, 110 min of DUT time through
// the CAN link, the table and the capture files -- read off its passport, every row against
// the band. Nothing here re-implements the procedure: bias and base error are formulas
// (3), (4) with the sign rule, the in-run B and the Allan terms those of the procedure's phases.
//
// One hour of raw data holds one realisation of the slow processes, so a single seed says
// little about the calibration: K's estimate scatters by about +-40 % between seeds and the
// x/y ratio by more (docs/plant.md, 20 seeds). The table is asserted on the median over a
// fixed set of nine seeds, 1..9, chosen before looking at any of them; each term must be
// identified on at least eight (B by the paper's method: six, see below). The paper profile's own
// seed is checked for identification below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "tests/plant/paper_run.hpp"

namespace rig::plant {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// One rig run per seed, two at a time (about 7 s of CPU each).
std::vector<calib::PaperRun> run_seeds(const std::vector<uint64_t>& seeds) {
  return calib::run_seeds(RIG_BINARY, calib::RunSpec{}, seeds, 2);
}

TEST(Calibration, PaperTableForTheDefaultProfileMedianOverNineSeeds) {
  const std::vector<uint64_t> seeds{1, 2, 3, 4, 5, 6, 7, 8, 9};
  const std::vector<calib::PaperRun> rs = run_seeds(seeds);
  std::vector<double> bias, base, gost, b_x, b_y, ratio, q, n, k;
  for (const calib::PaperRun& r : rs) {
    SCOPED_TRACE("seed " + std::to_string(r.seed));
    EXPECT_FALSE(r.value("r").has_value());  // R is not determinable from one hour (docs/method.md)
    bias.push_back(r.value("bias").value());
    base.push_back(r.value("base_error").value());
    gost.push_back(r.value("in_run_b_gost_100s").value());
    // The noise terms are medians over the seeds that identify them (passport units: g*h,
    // g*h^0.5, g/h^0.5); a term that a realisation cannot show is null with a reason, and
    // that may happen to one seed in nine (the paper's quartic finds no flat part).
    const auto bx = r.value("in_run_b_allan"), by = r.value("in_run_b_allan_filtered");
    if (bx) b_x.push_back(*bx);
    if (by) b_y.push_back(*by);
    if (bx && by) ratio.push_back(*bx / *by);
    if (auto v = r.value("q")) q.push_back(*v);
    if (auto v = r.value("n")) n.push_back(*v);
    if (auto v = r.value("k")) k.push_back(*v);
  }
  for (const auto* v : {&b_y, &q, &n, &k}) ASSERT_GE(v->size(), rs.size() - 1) << "a term is missing on 2+ seeds";
  // B by the paper's method needs the curve's minimum inside tau <= T/4. On the shipped
  // schedule (bring-up, homing, table moves, settling: the raw hour starts later than on the
  // re-implemented schedule this table was first measured with) seeds 2, 4 and 6 have none:
  // their N-K crossing lies beyond 836 s. Measured 6 of 9 (docs/plant.md); was 8 of 9.
  ASSERT_GE(b_x.size(), 6u) << "B (paper's method) missing on 4+ seeds";
  std::printf("median over seeds 1..9: bias %.4e, base %.4e, B GOST100 %.3e, B Allan %.3e (%zu), B filtered %.3e (%zu), "
              "ratio %.2f, Q %.3e, N %.3e, K %.3e (%zu)\n",
              median(bias), median(base), median(gost), median(b_x), b_x.size(), median(b_y), b_y.size(),
              median(ratio), median(q), median(n), median(k), k.size());
  // bias and base error, formulas (3), (4): within 1 %
  EXPECT_NEAR(median(bias), -5.0137e-4, 0.01 * 5.0137e-4);
  EXPECT_NEAR(median(base), 3.8549e-4, 0.01 * 3.8549e-4);
  // in-run B by GOST, 100 s blocks of the 30 min run: about 4e-6 (+-50 %)
  EXPECT_NEAR(median(gost), 4e-6, 0.5 * 4e-6);
  // in-run B by Allan (paper's method on x): 2.1e-6 (+-30 %)
  EXPECT_NEAR(median(b_x), 2.1e-6, 0.3 * 2.1e-6);
  // Q, N, K by the weighted fit on x: within a factor of 1.5 of the paper's
  auto within = [](double v, double target, const char* what) {
    EXPECT_GE(v, target / 1.5) << what << " = " << v << ", paper " << target;
    EXPECT_LE(v, target * 1.5) << what << " = " << v << ", paper " << target;
  };
  within(median(q), 6.3603e-10, "Q, g*h");
  within(median(n), 2.2306e-7, "N, g*h^0.5");
  within(median(k), 5.1167e-6, "K, g/h^0.5");
  // B with the output filter: about 0.86e-6 (+-30 %), the unfiltered/filtered ratio 2.5 +- 0.5
  // (the folded 1 kHz pick-up cut by |W_f(1 kHz)| = 0.39)
  EXPECT_NEAR(median(b_y), 0.86e-6, 0.3 * 0.86e-6);
  EXPECT_NEAR(median(ratio), 2.5, 0.5);
  // Every realisation: the filter lowers B.
  for (double x : ratio) EXPECT_GT(x, 1.5);
}

class CalibrationSeeds : public ::testing::TestWithParam<uint64_t> {};

TEST_P(CalibrationSeeds, KAndBothBAreIdentified) {
  calib::RunSpec spec;
  spec.seed = GetParam();
  const calib::PaperRun r = calib::run_rig(RIG_BINARY, spec);
  ASSERT_TRUE(r.value("k")) << r.passport["values"]["k"].dump();
  ASSERT_TRUE(r.value("in_run_b_allan")) << r.passport["values"]["in_run_b_allan"].dump();
  ASSERT_TRUE(r.value("in_run_b_allan_filtered")) << r.passport["values"]["in_run_b_allan_filtered"].dump();
  EXPECT_GT(*r.value("in_run_b_allan") / *r.value("in_run_b_allan_filtered"), 1.5);
  EXPECT_FALSE(r.value("r").has_value());
}
INSTANTIATE_TEST_SUITE_P(PaperProfileSeed, CalibrationSeeds, ::testing::Values(uint64_t{20181106}));

TEST(CalibrationLoop, SettlingAndBandwidth) {
  // The passport's loop phase, closed loop with the paper's W_f (the ci profile's filter, a
  // run of seconds): settling 0.003 s (+-20 %), bandwidth 492 Hz at 0.5 (+-5 %).
  calib::RunSpec spec;
  spec.base = "ci";
  const calib::PaperRun r = calib::run_rig(RIG_BINARY, spec);
  EXPECT_NEAR(r.value("settling_time").value(), 0.003, 0.2 * 0.003);
  EXPECT_NEAR(r.value("bandwidth_0p5").value(), 492, 0.05 * 492);
}

}  // namespace
}  // namespace rig::plant
