// The calibration table (docs/plant.md) for the default profile: the paper's whole
// procedure (110 min of DUT time) run on the model and measured by the rig's analysis
// (OADEV on the paper profile's log:100 grid + noise_terms, GOST in-run B), every row
// against the band.
//
// One hour of raw data holds one realisation of the slow processes, so a single seed says
// little about the calibration: K's estimate scatters by about +-40 % between seeds and the
// x/y ratio by more (docs/plant.md, 20 seeds). The table is asserted on the median over a
// fixed set of nine seeds, 1..9, chosen before looking at any of them; each term must be
// identified on at least eight. The paper profile's own seed is checked for identification below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <future>
#include <vector>

#include "plant/dut/loop_figures.hpp"
#include "analysis/noise_terms.hpp"
#include "tests/plant/paper_procedure.hpp"

namespace rig::plant {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// About 4 s of CPU per seed; two seeds at a time.
std::vector<calib::Result> run_seeds(const std::vector<uint64_t>& seeds) {
  std::vector<calib::Result> out(seeds.size());
  for (std::size_t i = 0; i < seeds.size(); i += 2) {
    std::vector<std::future<calib::Result>> f;
    for (std::size_t j = i; j < std::min(seeds.size(), i + 2); ++j)
      f.push_back(std::async(std::launch::async, [s = seeds[j]] {
        EmulatedDut dut(load_dut_params(nullptr), s);
        return calib::run(dut, calib::Spec{});
      }));
    for (std::size_t j = 0; j < f.size(); ++j) out[i + j] = f[j].get();
  }
  return out;
}

TEST(Calibration, PaperTableForTheDefaultProfileMedianOverNineSeeds) {
  const std::vector<uint64_t> seeds{1, 2, 3, 4, 5, 6, 7, 8, 9};
  const std::vector<calib::Result> rs = run_seeds(seeds);
  std::vector<double> bias, base, gost, b_x, b_y, ratio, q, n, k;
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const calib::Result& r = rs[i];
    SCOPED_TRACE("seed " + std::to_string(seeds[i]));
    ASSERT_EQ(r.x10.size(), 6u);
    ASSERT_EQ(r.x20.size(), 6u);
    EXPECT_FALSE(r.nt_x.R.value.has_value());  // R is not determinable from one hour (METHOD.md)
    bias.push_back(r.bias);
    base.push_back(r.base_error);
    gost.push_back(r.b_gost_100);
    // The noise terms are medians over the seeds that identify them (passport units: g*h,
    // g*h^0.5, g/h^0.5); a term that a realisation cannot show is null with a reason, and
    // that may happen to one seed in nine (the paper's quartic finds no flat part).
    if (r.nt_x.B.value) b_x.push_back(*r.nt_x.B.value);
    if (r.nt_y.B.value) b_y.push_back(*r.nt_y.B.value);
    if (r.nt_x.B.value && r.nt_y.B.value) ratio.push_back(*r.nt_x.B.value / *r.nt_y.B.value);
    if (r.nt_x.Q.value) q.push_back(*r.nt_x.Q.value / 3600.0);
    if (r.nt_x.N.value) n.push_back(*r.nt_x.N.value / 60.0);
    if (r.nt_x.K.value) k.push_back(*r.nt_x.K.value * 60.0);
  }
  for (const auto* v : {&b_x, &b_y, &q, &n, &k}) ASSERT_GE(v->size(), rs.size() - 1) << "a term is missing on 2+ seeds";
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
  EmulatedDut dut(load_dut_params(nullptr), GetParam());
  const calib::Result r = calib::run(dut, calib::Spec{});
  ASSERT_TRUE(r.nt_x.K.value) << r.nt_x.K.reason;
  ASSERT_TRUE(r.nt_x.B.value) << r.nt_x.B.reason;
  ASSERT_TRUE(r.nt_y.B.value) << r.nt_y.B.reason;
  EXPECT_GT(*r.nt_x.B.value / *r.nt_y.B.value, 1.5);
  EXPECT_FALSE(r.nt_x.R.value.has_value());
}
INSTANTIATE_TEST_SUITE_P(PaperProfileSeed, CalibrationSeeds, ::testing::Values(uint64_t{20181106}));

TEST(CalibrationLoop, SettlingAndBandwidth) {
  // closed loop with the paper's W_f: settling 0.003 s (+-20 %), bandwidth 492 Hz at 0.5 (+-5 %)
  const design::LoopFigures f = loop_figures(nullptr, design::paper_wf());
  EXPECT_NEAR(f.settling_time_s, 0.003, 0.2 * 0.003);
  EXPECT_NEAR(f.bandwidth_0p5_hz, 492, 0.05 * 492);
}

}  // namespace
}  // namespace rig::plant
