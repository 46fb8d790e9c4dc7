// The B1/R(n) rules of analysis/noise_id.hpp on hand-made series whose B1 ratio is
// known in closed form (the reference tables check them on measured data).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/noise_id.hpp"

namespace rig::analysis {
namespace {

std::vector<double> ramp(std::size_t n) {
  std::vector<double> z(n);
  for (std::size_t i = 0; i < n; ++i) z[i] = static_cast<double>(i);
  return z;
}

TEST(NoiseIdB1, RatioOfARampIsTheFlickerWalkExpectation) {
  // Sample variance n(n+1)/12 over AVAR 1/2: exactly B1(n, mu = 2).
  for (std::size_t n : {3u, 7u, 29u}) EXPECT_NEAR(b1_ratio(ramp(n)), b1_theory(static_cast<double>(n), 2), 1e-12);
  EXPECT_DOUBLE_EQ(b1_ratio(std::vector<double>{1, -1, 1, -1}), (4.0 / 3) / 2);  // var 4/3, AVAR 2
  EXPECT_DOUBLE_EQ(b1_ratio(std::vector<double>{5, 5, 5}), 1.0);                 // no variation: white FM
}

TEST(NoiseIdB1, BoundariesAreGeometricMeans) {
  const double n = 12;
  for (int mu = 2; mu > -2; --mu) {
    const double b = std::sqrt(b1_theory(n, mu) * b1_theory(n, mu - 1));
    EXPECT_EQ(b1_mu(b * 1.0001, n), mu) << mu;
    EXPECT_EQ(b1_mu(b * 0.9999, n), mu - 1) << mu;
  }
}

TEST(NoiseIdB1, NIsTheTermCountNotTheNumberOfAverages) {
  // Cs5071A OADEV AF 18784: 29 averages, 519422 terms, B1 = 1.664. Stable32 prints white FM
  // (alpha 0), which N = 519422 gives; N = 29 would give flicker FM.
  EXPECT_EQ(b1_mu(1.664, 29), 0);
  EXPECT_EQ(b1_mu(1.664, 519422), -1);
  B1Rules r;
  r.m = 7;
  r.max_factor = 100;
  r.n_terms = 7;  // a ramp of 7 averages: FW FM at N = 7 ...
  EXPECT_EQ(b1_rn_noise_id(ramp(7), r, nullptr).alpha, -3);
  r.n_terms = 40;  // ... but below the FW/RW boundary (74) at N = 40: RW FM
  EXPECT_EQ(b1_rn_noise_id(ramp(7), r, nullptr).alpha, -2);
}

TEST(NoiseIdB1, RepeatsThePreviousAlphaPastHalfTheLargestFactor) {
  B1Rules r;
  r.n_terms = 7;
  r.max_factor = 200;
  r.previous = 1;
  r.m = 100;  // 2m = max: still identified
  EXPECT_EQ(b1_rn_noise_id(ramp(7), r, nullptr).alpha, -3);
  r.m = 101;  // beyond: repeated, whatever the data say
  EXPECT_EQ(b1_rn_noise_id(ramp(7), r, nullptr).alpha, 1);
  r.previous.reset();  // nothing to repeat (first factor requested): identified
  EXPECT_EQ(b1_rn_noise_id(ramp(7), r, nullptr).alpha, -3);
  r.previous = -1;  // fewer than 2 averages: the previous alpha, else white FM
  r.m = 50;
  EXPECT_EQ(b1_rn_noise_id(std::vector<double>{1}, r, nullptr).alpha, -1);
  r.previous.reset();
  EXPECT_EQ(b1_rn_noise_id(std::vector<double>{1}, r, nullptr).alpha, 0);
}

TEST(NoiseIdB1, HadamardRefinesWalkNoisesOnTheDifferences) {
  // z = k^2: its differences are a ramp (FW FM), so the frequency itself is one order lower
  // still, random-run FM (alpha -4); B1 alone stops at FW FM (-3).
  std::vector<double> z(12);
  for (std::size_t k = 0; k < z.size(); ++k) z[k] = static_cast<double>(k * k);
  B1Rules r;
  r.m = 10;
  r.max_factor = 1000;
  r.n_terms = 10;
  EXPECT_EQ(b1_rn_noise_id(z, r, nullptr).alpha, -3);
  r.hadamard = true;
  EXPECT_EQ(b1_rn_noise_id(z, r, nullptr).alpha, -4);
  // Differences that read as PM leave a walk noise at RW FM (mu + 2 is not allowed below 1).
  for (std::size_t k = 0; k < z.size(); ++k) z[k] = static_cast<double>(k) + (k % 2 ? -1.0 : 1.0);
  EXPECT_EQ(b1_rn_noise_id(z, r, nullptr).alpha, -2);
}

TEST(NoiseIdB1, PhaseModulationNeedsRnToSplit) {
  const std::vector<double> z{1, -1, 1, -1, 1, -1, 1, -1};  // B1 = 8/7 / 2 < PM boundary
  B1Rules r;
  r.m = 64;
  r.max_factor = 1000;
  r.n_terms = 7;
  EXPECT_EQ(b1_rn_noise_id(z, r, nullptr).alpha, 1);  // no R(n) (non-modified types): flicker PM
  const double avar = 2;                               // non-overlapped AVAR of z
  const double bound = std::sqrt(rn_theory(64, 2) * rn_theory(64, 1));
  EXPECT_EQ(b1_rn_noise_id(z, r, [&] { return 0.5 * bound * avar; }).alpha, 2);  // R(n) ~ 1/m: white PM
  EXPECT_EQ(b1_rn_noise_id(z, r, [&] { return 2.0 * bound * avar; }).alpha, 1);
  EXPECT_EQ(b1_rn_noise_id(z, r, [] { return -1.0; }).alpha, 1);  // Mod AVAR not available
}

TEST(NoiseIdAcf, ScalesR1ByNMinus1OverNAndAddsTwoForPhase) {
  const std::vector<double> x{1, 0, 0, 0, 0};  // r1 = -0.05, stationary at once
  const double r1 = lag1_acf(x) * 4 / 5;
  const NoiseId f = acf_noise_id(x, false, 2), p = acf_noise_id(x, true, 2);
  EXPECT_DOUBLE_EQ(f.rho, r1 / (1 + r1));
  EXPECT_EQ(f.d, 0);
  EXPECT_EQ(f.alpha, 0);
  EXPECT_EQ(p.alpha, 2);
  // A ramp is non-stationary until differenced once (a constant: r1 = 0): alpha -2.
  const NoiseId id = acf_noise_id(ramp(40), false, 2);
  EXPECT_EQ(id.d, 1);
  EXPECT_EQ(id.alpha, -2);
}

}  // namespace
}  // namespace rig::analysis
