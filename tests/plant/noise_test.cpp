// Noise generators, and recovery of injected noise terms by the rig's analysis:
// for several parameter sets the emulated output is analysed (OADEV + noise_terms)
// and each injected term must be found within its bounds.
#include <gtest/gtest.h>

#include <cmath>

#include "plant/dut/emulated_dut.hpp"
#include "plant/dut/noise.hpp"
#include "procedures/analysis/psd.hpp"
#include "rig/core/toml_util.hpp"
#include "tests/plant/paper_procedure.hpp"

namespace rig::plant {
namespace {

TEST(Noise, RngIsDeterministicAndNormalHasUnitMoments) {
  noise::Rng a(1, 2), b(1, 2), c(1, 3);
  EXPECT_EQ(a.next(), b.next());
  EXPECT_NE(a.next(), c.next());
  double s = 0, s2 = 0, s4 = 0;
  const int n = 1'000'000;
  for (int i = 0; i < n; ++i) {
    const double v = a.normal();
    s += v, s2 += v * v, s4 += v * v * v * v;
  }
  EXPECT_NEAR(s / n, 0, 0.005);
  EXPECT_NEAR(s2 / n, 1, 0.005);
  EXPECT_NEAR(s4 / n, 2.7, 0.05);  // Irwin-Hall(4): kurtosis 3 - 1.2/4
}

TEST(Noise, RoundHalfEvenMatchesNearbyint) {
  for (double v : {-2.5, -1.5, -0.5, 0.49, 0.5, 1.5, 2.5, 1e9 + 0.7, -123.25})
    EXPECT_EQ(noise::round_half_even(v), std::nearbyint(v)) << v;
}

TEST(Noise, FlickerBankIsFlatOverItsDecades) {
  noise::Rng r(3, 0);
  const noise::FlickerBank fb(1e-6, 0.5, 2e4, 1e-3, r);
  for (double tau : {10.0, 30.0, 100.0, 300.0, 1000.0}) EXPECT_NEAR(fb.adev(tau) / 0.664e-6, 1.0, 0.08) << tau;
  EXPECT_LT(fb.adev(0.01), 0.5 * 0.664e-6);  // below tau_min: not flicker any more
}

TEST(Noise, LineBandStaysInItsBand) {
  noise::Rng r(4, 0);
  noise::LineBand band(795, 970, 6, 2.0, 1e-3, 10000, 1e-3, r);
  std::vector<double> v(400000);
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i % 10 == 0) band.update_envelopes(r);
    v[i] = band.step();
  }
  double s2 = 0;
  for (double e : v) s2 += e * e;
  EXPECT_NEAR(std::sqrt(s2 / v.size()), 1e-3, 0.3e-3);
  analysis::WelchOptions wo;
  wo.window = analysis::Window::Blackman;  // low side lobes: what is left near 1 kHz is the generator's
  const analysis::Psd p = analysis::welch(v, 10000, wo);
  double in = 0, near_1k = 0;
  for (std::size_t i = 0; i < p.f_hz.size(); ++i) {
    if (p.f_hz[i] >= 780 && p.f_hz[i] <= 985) in += p.psd[i];
    if (p.f_hz[i] >= 990 && p.f_hz[i] <= 1010) near_1k += p.psd[i];
  }
  // only the Lorentzian skirts of the wandering lines (line width 1/(pi coherence)) reach
  // 990-1010 Hz, the part that sampling at 1 kHz folds to near-DC
  EXPECT_LT(near_1k, 1e-3 * in);
}

// A DUT with every noise source off except those given.
EmulatedDut quiet_dut(const std::string& extra, uint64_t seed) {
  const std::string text =
      "[noise]\nsense_white_g_rthz = 0\ninput_white_g_rthz = 0\nflicker_b_g = 0\nrrw_k_g_per_rts = 0\n"
      "ramp_r_g_per_s = 0\nbias_tempco_g_per_c = 0\nvibration_rms_g = 0\nburst_peak_g = 0\n"
      "interference_rms_g = 0\npolling_b_g = 0\noutput_lsb_g = 0\nsense_adc_bits = 30\n";
  toml::table t = cfg::parse_string(text, "quiet.toml");
  cfg::merge_into(t, cfg::parse_string(extra, "test.toml"));
  return EmulatedDut(load_dut_params(&t), seed);
}

analysis::NoiseTerms analyse(EmulatedDut& d, double seconds) {
  std::vector<double> x(static_cast<std::size_t>(seconds * 1000));
  for (double& v : x) {
    double y;
    d.next(v, y);
  }
  return calib::allan_terms(x, 1000);
}

// true value inside the reported 68 % bounds widened to about 2 sigma, and within `rel`.
void expect_found(const analysis::Term& t, double truth, double rel, const char* what) {
  ASSERT_TRUE(t.value.has_value()) << what << ": " << t.reason;
  EXPECT_NEAR(*t.value / truth, 1.0, rel) << what << " = " << *t.value << ", injected " << truth;
  if (t.lo && t.hi) {
    EXPECT_GE(truth, *t.value - 2 * (*t.value - *t.lo) - 0.02 * truth) << what;
    EXPECT_LE(truth, *t.value + 2 * (*t.hi - *t.value) + 0.02 * truth) << what;
  }
}

struct WhiteCase {
  double density;  // sense-channel white density, g/sqrt(Hz)
  uint64_t seed;
};
class WhiteRecovery : public ::testing::TestWithParam<WhiteCase> {};

TEST_P(WhiteRecovery, FindsN) {
  // white at 10 kHz, one-sided density d, sampled at 1 kHz: sd = d sqrt(5000), N = sd sqrt(1 ms) = d sqrt(5)
  EmulatedDut d = quiet_dut("[noise]\nsense_white_g_rthz = " + std::to_string(GetParam().density) + "\n", GetParam().seed);
  const analysis::NoiseTerms nt = analyse(d, 300);
  expect_found(nt.N, GetParam().density * std::sqrt(5.0), 0.05, "N");
}
INSTANTIATE_TEST_SUITE_P(Sets, WhiteRecovery, ::testing::Values(WhiteCase{2e-5, 1}, WhiteCase{2e-4, 2}));

TEST(NoiseRecovery, FindsNAndK) {
  const double dens = 2e-5, k = 2e-6;  // crossover sqrt(3) N / K = 39 s
  EmulatedDut d = quiet_dut("[noise]\nsense_white_g_rthz = 2e-5\nrrw_k_g_per_rts = 2e-6\n", 3);
  const analysis::NoiseTerms nt = analyse(d, 1200);
  expect_found(nt.N, dens * std::sqrt(5.0), 0.08, "N");
  expect_found(nt.K, k, 0.35, "K");
}

TEST(NoiseRecovery, FindsQFromTheVelocityQuantiser) {
  // output words with the remainder carried: x_n = v_n + e_{n-1} - e_n, Q = lsb tau0 / sqrt(12);
  // The white noise (sd 0.35 LSB per sample) dithers the rounding so that its error is
  // uniform and white, while Q still dominates at the shortest tau (Q dominates at tau0
  // only if sd_white < LSB/2, so the window is narrow).
  const double lsb = 6e-2;
  EmulatedDut d = quiet_dut("[noise]\nsense_white_g_rthz = 3e-4\noutput_lsb_g = 6e-2\n", 4);
  const analysis::NoiseTerms nt = analyse(d, 300);
  expect_found(nt.Q, lsb * 1e-3 / std::sqrt(12.0), 0.15, "Q");
  expect_found(nt.N, 3e-4 * std::sqrt(5.0), 0.15, "N");
}

TEST(NoiseRecovery, FindsBFromFlicker) {
  for (uint64_t seed : {5u, 6u}) {
    EmulatedDut d = quiet_dut("[noise]\nsense_white_g_rthz = 1e-6\nflicker_b_g = 2e-5\n", seed);
    const analysis::NoiseTerms nt = analyse(d, 1200);
    ASSERT_TRUE(nt.B.value.has_value()) << nt.B.reason;
    EXPECT_NEAR(*nt.B.value / 2e-5, 1.0, 0.3) << "seed " << seed << " tau_cp " << nt.tau_cp_s.value_or(0);
  }
}

}  // namespace
}  // namespace rig::plant
