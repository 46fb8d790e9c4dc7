// Loop figures from a recorded step (analysis/loop_response.hpp) against closed forms: a
// first-order discrete system's settling time and 0.5-level bandwidth, the normalisation of a
// recorded step, and the repeated-step interval (Student's t of GOST R 8.736 and the resolution).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "analysis/loop_response.hpp"

using namespace rig::analysis;

namespace {
// y[k] = a y[k-1] + (1 - a) u[k]: unit-step response 1 - a^(k+1).
std::vector<double> first_order_step(double a, std::size_t n) {
  std::vector<double> h(n);
  for (std::size_t k = 0; k < n; ++k) h[k] = 1 - std::pow(a, static_cast<double>(k + 1));
  return h;
}
}  // namespace

TEST(LoopResponse, FirstOrderSettlingTimeIsTheClosedForm) {
  const double a = 0.9, dt = 1e-4;
  const auto h = first_order_step(a, 2000);
  // |h[k] - 1| = a^(k+1) > band while k + 1 < ln(band) / ln(a): the last sample outside is
  // k = floor(ln(band) / ln(a)) - 1 (at time k dt), and the settling time one period later.
  const double want = std::floor(std::log(0.05) / std::log(a)) * dt;
  EXPECT_NEAR(settling_time(h, dt, 1.0), want, 1e-12);
  EXPECT_NEAR(settling_time(h, dt, 1.0, 0.02), std::floor(std::log(0.02) / std::log(a)) * dt, 1e-12);
  EXPECT_EQ(settling_time(std::vector<double>(10, 1.0), dt, 1.0), 0.0) << "never outside the band";
}

TEST(LoopResponse, FirstOrderBandwidthAtHalfIsTheClosedForm) {
  const double a = 0.9, rate = 10000;
  const auto h = first_order_step(a, 2000);
  // |H(w)|^2 = (1-a)^2 / (1 - 2a cos w + a^2) = 1/4.
  const double w = std::acos((1 + a * a - 4 * (1 - a) * (1 - a)) / (2 * a));
  const double want = w * rate / (2 * std::numbers::pi);
  const StepFigures f = step_figures(h, rate);
  EXPECT_NEAR(f.final_value, 1.0, 1e-12);
  EXPECT_NEAR(f.bandwidth_0p5_hz, want, 0.05);  // 1 Hz grid, linear between the points
  EXPECT_EQ(f.overshoot, 0.0);
  EXPECT_NEAR(f.amplitude.amp.front(), 1.0, 1e-3);
}

// The amplitude curve is the passport's (bandwidth) and analysis.json's (curves): computing
// several frequencies side by side must give the bits of the plain one-frequency-at-a-time
// std::complex sum, on every frequency (also a last, partial group of lanes).
TEST(LoopResponse, AmplitudeCurveEqualsTheOneFrequencyAtATimeSumBitForBit) {
  std::vector<double> h(997);
  double y = 0, w = 0.3;
  for (std::size_t k = 0; k < h.size(); ++k) {  // an underdamped second-order step with a wobble
    w = 0.97 * w + 0.01 * std::sin(0.37 * static_cast<double>(k));
    y += 0.2 * (1 - y) + 0.05 * w;
    h[k] = y;
  }
  const double rate = 10000, final = 0.93;
  for (double step : {1.0, 7.0, 1250.0}) {
    const AmplitudeCurve c = step_amplitude_response(h, rate, final, step);
    std::vector<double> d(h.size());
    for (std::size_t k = 0; k < h.size(); ++k) d[k] = h[k] - (k ? h[k - 1] : 0.0);
    std::size_t i = 0;
    for (double f = step; f <= rate / 2; f += step, ++i) {
      const std::complex<double> rot = std::polar(1.0, -2 * std::numbers::pi * f / rate);
      std::complex<double> z = 1, acc = 0;
      for (double v : d) {
        acc += v * z;
        z *= rot;
      }
      ASSERT_LT(i, c.f_hz.size());
      ASSERT_EQ(c.f_hz[i], f);
      ASSERT_EQ(c.amp[i], std::abs(acc) / std::abs(final)) << "step " << step << " Hz, f " << f << " Hz";
    }
    EXPECT_EQ(c.f_hz.size(), i);
    EXPECT_EQ(c.amp.size(), i);
  }
}

// The loop test reads the bandwidth up to its crossing only and the curve at the plotted
// points only: the same values as read off the whole curve.
TEST(LoopResponse, PartialCurveAndCrossingEqualTheWholeCurvesBitForBit) {
  for (double a : {0.9, 0.97}) {
    std::vector<double> h(1500);
    double y = 0;
    for (std::size_t k = 0; k < h.size(); ++k) {
      y = a * y + (1 - a) * (1 + 0.02 * std::sin(0.05 * static_cast<double>(k)));
      h[k] = y;
    }
    const double rate = 10000, final = final_value(h);
    const AmplitudeCurve whole = step_amplitude_response(h, rate, final);
    const double want = crossing_frequency(whole.f_hz, whole.amp, 0.5);
    ASSERT_GT(want, 0.0);
    EXPECT_EQ(step_crossing_frequency(h, rate, final, 0.5), want);
    EXPECT_EQ(step_crossing_frequency(h, rate, final, 1e-9), 0.0) << "never crosses";
    const std::vector<std::size_t> at = {0, 1, 7, 8, 9, 500, 2499, whole.f_hz.size() - 1};
    std::vector<double> f;
    for (std::size_t i : at) f.push_back(whole.f_hz[i]);
    const AmplitudeCurve part = step_amplitude_at(h, rate, final, f);
    ASSERT_EQ(part.amp.size(), at.size());
    for (std::size_t j = 0; j < at.size(); ++j) EXPECT_EQ(part.amp[j], whole.amp[at[j]]) << at[j];
    const StepFigures full = step_figures(h, rate), sparse = step_figures(h, rate, kStepSettlingBand, f);
    EXPECT_EQ(sparse.bandwidth_0p5_hz, full.bandwidth_0p5_hz);
    EXPECT_EQ(sparse.settling_time_s, full.settling_time_s);
    EXPECT_EQ(sparse.amplitude.f_hz, f);
    EXPECT_EQ(amplitude_grid(rate), whole.f_hz);
  }
}

TEST(LoopResponse, UnitStepRemovesTheBaselineAndScalesByTheAmplitude) {
  std::vector<double> r = {0.2, 0.2, 0.2, 0.2, -1.8, -2.8, -2.8};
  const auto h = unit_step(r, 4, -2.0);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_DOUBLE_EQ(h[0], 1.0);
  EXPECT_DOUBLE_EQ(h[2], 1.5);
  EXPECT_DOUBLE_EQ(final_value(h, 0.5), 1.5);
  EXPECT_THROW(unit_step(r, 0, 1.0), std::invalid_argument);
  EXPECT_THROW(unit_step(r, 7, 1.0), std::invalid_argument);
  EXPECT_THROW(unit_step(r, 2, 0.0), std::invalid_argument);
}

TEST(LoopResponse, RepeatedFigureIsStudentsIntervalWidenedByTheResolution) {
  const std::vector<double> v = {3.0, 3.2, 3.1, 3.1, 3.1};
  const RepeatedFigure r = repeated_figure(v, 0.1);
  EXPECT_DOUBLE_EQ(r.value, 3.1);
  EXPECT_EQ(r.n, 5u);
  const double sd = std::sqrt(0.02 / 4);
  EXPECT_NEAR(r.sd, sd, 1e-12);
  const double t = 2.7764451051977987;  // Student's t, 0.975, 4 degrees of freedom
  EXPECT_NEAR(r.hi - r.value, std::hypot(t * sd / std::sqrt(5.0), 0.05), 1e-9);
  EXPECT_NEAR(r.value - r.lo, r.hi - r.value, 1e-12);
  const RepeatedFigure one = repeated_figure(std::vector<double>{3.0}, 0.1);
  EXPECT_NEAR(one.hi - one.lo, 0.1, 1e-12) << "one step: the resolution only";
  EXPECT_THROW(repeated_figure(std::vector<double>{}, 0.1), std::invalid_argument);
}
