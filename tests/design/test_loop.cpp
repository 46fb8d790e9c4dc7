// The loop as designed: the regulator's biquad equals its PI x lead product, the loop
// figures are read off their own curves with the one settling band, the loop/regulator
// tables are read with clear errors. (The loop model against simulation: tests/plant.)
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "design/filter.hpp"
#include "design/loop_figures.hpp"
#include "design/loop_model.hpp"
#include "design/loop_params.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::design {
namespace {

using cd = std::complex<double>;

// W_рег(e^{jwT}) = Kc (1 + a z/(z-1)) (1 - zl z^-1)/(1 - pl z^-1), written out directly.
cd regulator_formula(const RegulatorParams& r, double fs, double f_hz) {
  const double T = 1 / fs;
  const cd z = std::polar(1.0, 2 * std::numbers::pi * f_hz / fs);
  const double a = 2 * std::numbers::pi * r.integral_corner_hz * T;
  const double zl = std::exp(-2 * std::numbers::pi * r.lead_zero_hz * T);
  const double pl = std::exp(-2 * std::numbers::pi * r.lead_pole_hz * T);
  return r.gain_a_per_v * (1.0 + a * z / (z - 1.0)) * (1.0 - zl / z) / (1.0 - pl / z);
}

TEST(Regulator, BiquadIsThePiTimesLeadProduct) {
  RegulatorParams r{1.3e-2, 20, 145, 3150};
  const double fs = 10000;
  for (double integral : {20.0, 0.0}) {  // 0: no integrator, the (1 - z^-1) factors cancel
    r.integral_corner_hz = integral;
    FilterConfig f;
    f.rate_hz = fs;
    f.sections = {regulator_biquad(r, fs)};
    for (double fr : {1.0, 50.0, 500.0, 3000.0}) {
      const cd want = regulator_formula(r, fs, fr);
      EXPECT_LT(std::abs(response(f, fr) - want), 1e-9 * std::abs(want)) << integral << " " << fr;
    }
    if (integral == 0) {
      EXPECT_EQ(f.sections[0].b2, 0.0);
      EXPECT_EQ(f.sections[0].a2, 0.0);
    }
  }
  const LoopModel m(LoopParams{}, r);
  EXPECT_EQ(m.regulator().b1, regulator_biquad(r, LoopParams{}.loop_rate_hz).b1);
}

TEST(LoopFigures, AreReadOffTheirOwnCurvesWithTheOneBand) {
  const LoopParams lp;
  const RegulatorParams rp;
  FilterConfig off;
  off.enabled = false;
  const LoopFigures g = loop_figures(lp, rp, off);
  EXPECT_EQ(g.step_y, g.step_x);  // no filter: y is x
  EXPECT_EQ(g.amp_y, g.amp_x);
  EXPECT_NEAR(g.dc_gain, 1.0, 1e-9);  // integral action

  const LoopFigures f = loop_figures(lp, rp, paper_wf());
  const double dt = 1 / lp.loop_rate_hz;
  EXPECT_EQ(f.settling_band, kSettlingBand);
  EXPECT_EQ(f.settling_time_s, analysis::settling_time(f.step_y, dt, f.dc_gain, kSettlingBand));  // h(inf) = DC gain
  EXPECT_TRUE(f.settled);
  EXPECT_EQ(f.step_window_s, 0.05);  // the paper's filter settles in the first 50 ms
  EXPECT_GT(f.settling_time_s, 0.0);
  // Read off the grid, then bisected on the response to its last digits (the grid's interpolation
  // held about 5 of the 6 printed: a metrologist's review).
  EXPECT_NEAR(f.bandwidth_0p5_hz, bandwidth_at(f.freq_hz, f.amp_y, 0.5), 1e-4 * f.bandwidth_0p5_hz);
  const LinearLoop lin = LoopModel(lp, rp).linear();
  const auto amp_y = [&](double fr) { return std::abs(loop_response(lin, fr) * response(paper_wf(), fr)); };
  EXPECT_NEAR(amp_y(f.bandwidth_0p5_hz), 0.5, 1e-10);
  EXPECT_NEAR(amp_y(f.bandwidth_3db_hz), 1 / std::sqrt(2.0), 1e-10);
  EXPECT_LT(f.bandwidth_3db_hz, f.bandwidth_0p5_hz);
  EXPECT_LT(f.bandwidth_0p5_hz, g.bandwidth_0p5_hz);  // the low-pass narrows the band
  ASSERT_EQ(f.step_t_s.size(), f.step_y.size());
  ASSERT_EQ(f.freq_hz.size(), f.amp_y.size());

  // The filter runs at the loop rate whatever rate its description names.
  FilterConfig at_1k = paper_wf();
  at_1k.rate_hz = 1000;
  EXPECT_EQ(loop_figures(lp, rp, at_1k).bandwidth_0p5_hz, f.bandwidth_0p5_hz);
}

// A filter far slower than the loop: the loop is flat there, so the figures are the filter's
// own closed forms. With a 50 ms step and a grid from 1 Hz, butter1@0.2 read "0 Hz" and a
// settling time of 47 ms (a review); the window now grows and the grid reaches below the cut-off.
TEST(LoopFigures, FollowALowCutOffInTimeAndFrequency) {
  const LoopParams lp;
  const RegulatorParams rp;
  const double fc = 0.2, tau = 1 / (2 * std::numbers::pi * fc), dt = 1 / lp.loop_rate_hz;
  const LoopFigures f = loop_figures(lp, rp, butterworth_lowpass(1, fc, lp.loop_rate_hz));
  EXPECT_TRUE(f.settled);
  EXPECT_NEAR(f.settling_time_s, tau * std::log(20.0), 0.002 * tau);  // 1 - exp(-t/tau) enters 5 % at tau ln 20
  EXPECT_LE(2 * f.settling_time_s, f.step_window_s);
  EXPECT_NEAR(f.bandwidth_3db_hz, fc, 1e-3 * fc);
  EXPECT_NEAR(f.bandwidth_0p5_hz, std::sqrt(3.0) * fc, 1e-3 * fc);  // 1/sqrt(1 + (f/fc)^2) = 0.5
  EXPECT_LT(f.freq_hz.front(), fc / 10);
  EXPECT_EQ(f.overshoot, 0.0);
  // The curves are every 2^k-th sample of the window, at most 5000 points, t and y in step.
  ASSERT_EQ(f.step_t_s.size(), f.step_y.size());
  ASSERT_EQ(f.step_x.size(), f.step_y.size());
  EXPECT_LE(f.step_y.size(), 5000u);
  EXPECT_GT(f.step_y.size(), 2500u);
  EXPECT_GT(f.step_t_s.back(), 0.99 * f.step_window_s);
  EXPECT_EQ(f.step_t_s[1] - f.step_t_s[0], f.step_t_s[2] - f.step_t_s[1]);

  // butter2@5: a step simulated well past its settling gives the same figure (47.9 ms before).
  const FilterConfig b2 = butterworth_lowpass(2, 5, lp.loop_rate_hz);
  const std::vector<double> long_y = apply_filter(b2, loop_step(LoopModel(lp, rp).linear(), 20000));
  const LoopFigures g = loop_figures(lp, rp, b2);
  EXPECT_EQ(g.settling_time_s, analysis::settling_time(long_y, dt, 1.0, kSettlingBand));
  EXPECT_GT(g.settling_time_s, 0.08);

  // Slower than the longest step can show: not settled, the figure a lower bound.
  const LoopFigures s = loop_figures(lp, rp, butterworth_lowpass(1, 1e-4, lp.loop_rate_hz));
  EXPECT_FALSE(s.settled);
  EXPECT_GT(s.settling_time_s, s.step_window_s / 2);
  EXPECT_EQ(s.step_window_s, 409.6);
  EXPECT_NEAR(s.bandwidth_3db_hz, 1e-4, 1e-7);
  // An unstable loop (the regulator's gain far too high) is said to be, not given a settling time.
  RegulatorParams hot = rp;
  hot.gain_a_per_v = 1000;
  const LoopFigures u = loop_figures(lp, hot, paper_wf());
  EXPECT_GT(u.largest_pole, 1.0);
  EXPECT_FALSE(u.settled);
  EXPECT_LT(f.largest_pole, 1.0);
  // The grid reaches the lowest cut-off a filter may have (1e-9 Hz read "0 Hz" with a grid to 1e-9).
  EXPECT_NEAR(loop_figures(lp, rp, butterworth_lowpass(1, 1e-9, lp.loop_rate_hz)).bandwidth_3db_hz, 1e-9, 1e-12);
}

// The figures' step is loop_step through apply_filter, bit for bit, at the points it keeps (every
// 2^k-th sample from 0): it is simulated as one run of its own, so a test holds the two together.
TEST(LoopFigures, TheStepIsLoopStepThroughTheFilter) {
  const LoopParams lp;
  const RegulatorParams rp;
  for (const FilterConfig& w : {paper_wf(), butterworth_lowpass(1, 0.2, lp.loop_rate_hz)}) {
    const LoopFigures f = loop_figures(lp, rp, w);
    const auto n = static_cast<std::size_t>(std::lround(f.step_window_s * lp.loop_rate_hz));
    const std::vector<double> x = loop_step(LoopModel(lp, rp).linear(), n), y = apply_filter(w, x);
    const auto stride = f.step_t_s.size() > 1
                            ? static_cast<std::size_t>(std::lround((f.step_t_s[1] - f.step_t_s[0]) * lp.loop_rate_hz))
                            : 1;
    ASSERT_EQ(f.step_y.size(), (n + stride - 1) / stride);
    for (std::size_t i = 0; i < f.step_y.size(); ++i) {
      ASSERT_EQ(f.step_x[i], x[i * stride]) << i;
      ASSERT_EQ(f.step_y[i], y[i * stride]) << i;
      ASSERT_EQ(f.step_t_s[i], static_cast<double>(i * stride) * (1.0 / lp.loop_rate_hz)) << i;
    }
    EXPECT_EQ(f.settling_time_s, analysis::settling_time(y, 1 / lp.loop_rate_hz, f.dc_gain, kSettlingBand));
  }
}

// The longest step is 4 096 000 loop periods at any loop rate (a 1 MHz loop's doublings stopped at
// 3.2e6), and an integrator cancelled by its zero is not an unstable pole (1 + 2e-14 was).
TEST(LoopFigures, TheCapIsInLoopPeriodsAndRoundingIsNotInstability) {
  LoopParams fast;
  fast.loop_rate_hz = 1e6;
  const LoopFigures f = loop_figures(fast, RegulatorParams{}, butterworth_lowpass(1, 1e-3, fast.loop_rate_hz));
  EXPECT_FALSE(f.settled);
  EXPECT_EQ(f.step_window_s, 4.096);
  RegulatorParams cancelled;
  cancelled.integral_corner_hz = 1e-12;
  const LoopFigures g = loop_figures(LoopParams{}, cancelled, paper_wf());
  EXPECT_TRUE(g.stable()) << g.largest_pole;  // (its integrator's mode is slower than any window)
}

TEST(LoopParams, TablesAreReadWithClearErrors) {
  LoopParams lp;
  RegulatorParams rp;
  read_loop_params(cfg::parse_string("loop_rate_hz = 20000\nadc_bits = 18\n", "d.toml"), "dut.loop", lp);
  EXPECT_EQ(lp.loop_rate_hz, 20000);
  EXPECT_EQ(lp.adc_bits, 18);
  EXPECT_EQ(lp.output_rate_hz, 1000);  // absent keys keep their value
  read_regulator_params(cfg::parse_string("lead_pole_hz = 2000\n", "d.toml"), "dut.regulator", rp);
  EXPECT_EQ(rp.lead_pole_hz, 2000);
  auto error_of = [](const std::string& text) {
    LoopParams p;
    try {
      read_loop_params(cfg::parse_string(text, "d.toml"), "dut.loop", p);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("output_rate_hz = 3000\n").find("integer multiple"), std::string::npos);
  EXPECT_NE(error_of("\nadc_bits = 2\n").find("d.toml:2"), std::string::npos);
  const std::string unknown = error_of("inertia = 1\n");
  EXPECT_NE(unknown.find("inertia"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("dut.loop"), std::string::npos) << unknown;
}

}  // namespace
}  // namespace rig::design
