// Filter quality: the paper's W_f(z) reproduces docs/method.md's derived figures; Butterworth
// designs match the bilinear-transform coefficients (scipy.signal.butter) and |H(fc)| = 0.707;
// settling time against the closed form of a first-order step response.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/filter.hpp"

namespace rig::analysis {
namespace {

TEST(PaperFilter, ReproducesTheDerivedFigures) {
  const auto f = paper_wf();
  EXPECT_NEAR(std::abs(response(f, 0)), 1.0, 1e-5);
  EXPECT_NEAR(std::abs(response(f, 70)), 0.99, 0.005);
  EXPECT_NEAR(std::abs(response(f, 500)), 0.71, 0.005);
  EXPECT_NEAR(std::abs(response(f, 800)), 0.50, 0.01);  // 0.495: docs/method.md rounds
  EXPECT_NEAR(std::abs(response(f, 970)), 0.40, 0.005);
  EXPECT_NEAR(std::abs(response(f, 1000)), 0.39, 0.005);
  EXPECT_NEAR(bandwidth_at_level(f, 1 / std::sqrt(2.0)), 506, 1.0);
  EXPECT_NEAR(bandwidth_at_level(f, 0.5), 792, 2.0);  // docs/method.md: 0.50 at 800 Hz (rounded)
  // Both poles real at z = 0.6141 (critically damped): the step response never overshoots.
  const std::vector<double> ones(200, 1.0);
  const auto step = analysis::apply(f, ones);
  for (double v : step) EXPECT_LE(v, 1.0 + 1e-6);
  EXPECT_GT(settling_time(f, 0.02), 0.0);
  EXPECT_LT(settling_time(f, 0.02), 0.003);  // the paper: about 3 ms
  EXPECT_LT(settling_time(f, 0.05), settling_time(f, 0.02));
}

TEST(PaperFilter, SameCoefficientsAtOneKilohertzCutOffAtFiftyOne) {
  auto f = paper_wf();
  f.rate_hz = 1000;
  EXPECT_NEAR(bandwidth_at_level(f, 1 / std::sqrt(2.0)), 50.6, 0.2);
}

TEST(Butterworth, SecondOrderMatchesScipy) {
  // scipy.signal.butter(2, 500, fs=10000): b = [0.02008337, 0.04016673, 0.02008337],
  // a = [1, -1.56101808, 0.64135154].
  const auto f = butterworth_lowpass(2, 500, 10000);
  ASSERT_EQ(f.sections.size(), 1u);
  EXPECT_NEAR(f.sections[0].b0, 0.02008337, 1e-8);
  EXPECT_NEAR(f.sections[0].b1, 0.04016673, 1e-8);
  EXPECT_NEAR(f.sections[0].a1, -1.56101808, 1e-8);
  EXPECT_NEAR(f.sections[0].a2, 0.64135154, 1e-8);
}

TEST(Butterworth, EveryOrderHasUnitDcGainAndMinus3dBAtTheCutOff) {
  for (int order = 1; order <= 4; ++order) {
    const auto f = butterworth_lowpass(order, 500, 10000);
    EXPECT_EQ(f.sections.size(), static_cast<std::size_t>((order + 1) / 2));
    EXPECT_NEAR(std::abs(response(f, 0)), 1.0, 1e-12) << order;
    EXPECT_NEAR(std::abs(response(f, 500)), 1 / std::sqrt(2.0), 1e-9) << order;
    EXPECT_NEAR(bandwidth_at_level(f, 1 / std::sqrt(2.0)), 500, 0.01) << order;
    // Steeper with order: attenuation at 2 fc grows.
    if (order > 1) {
      EXPECT_LT(std::abs(response(f, 1000)), std::abs(response(butterworth_lowpass(order - 1, 500, 10000), 1000)));
    }
  }
  EXPECT_THROW(butterworth_lowpass(5, 500, 10000), std::invalid_argument);
  EXPECT_THROW(butterworth_lowpass(2, 5000, 10000), std::invalid_argument);
}

TEST(Settling, FirstOrderMatchesTheClosedForm) {
  // y[n] = (1 - a) x[n] + a y[n-1]: step response 1 - a^(n+1); within 2 % once a^(n+1) <= 0.02.
  const double a = 0.9;
  rig::FilterConfig f;
  f.rate_hz = 1000;
  f.sections.push_back({1 - a, 0, 0, -a, 0});
  const int n = static_cast<int>(std::ceil(std::log(0.02) / std::log(a))) - 1;  // first index inside
  EXPECT_NEAR(settling_time(f, 0.02), n / 1000.0, 1e-12);
  rig::FilterConfig off = f;
  off.enabled = false;
  EXPECT_EQ(settling_time(off), 0.0);
  EXPECT_EQ(std::abs(response(off, 123)), 1.0);
}

TEST(Apply, CascadeIsTheProductOfSectionsAndRmsIsTheMeanSquare) {
  const auto f = butterworth_lowpass(4, 100, 1000);
  std::vector<double> x(2000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::sin(2 * M_PI * 300 * static_cast<double>(i) / 1000);
  const auto y = analysis::apply(f, x);
  // After the transient the 300 Hz tone is attenuated by |H(300)|.
  const double gain = std::abs(response(f, 300));
  const std::span<const double> tail(y.data() + 1000, 1000);
  EXPECT_NEAR(rms(tail), gain / std::sqrt(2.0), 0.02 * gain);
  EXPECT_NEAR(rms(std::vector<double>({3.0, 4.0})), std::sqrt(12.5), 1e-12);
  EXPECT_EQ(rms(std::vector<double>()), 0.0);
}

}  // namespace
}  // namespace rig::analysis
