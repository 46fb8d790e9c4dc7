// Noise generators, and recovery of injected noise terms by the rig's analysis:
// for several parameter sets the emulated output is analysed (OADEV + noise_terms)
// and each injected term must be found within its bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "plant/dut/emulated_dut.hpp"
#include "design/quantise.hpp"
#include "plant/dut/noise.hpp"
#include "analysis/psd.hpp"
#include "rig/core/toml_util.hpp"
#include "procedures/acceptance/method.hpp"

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
    EXPECT_EQ(design::round_half_even(v), std::nearbyint(v)) << v;
}

TEST(Noise, FlickerBankIsFlatOverItsDecades) {
  noise::Rng r(3, 0);
  const noise::FlickerBank fb(1e-6, 0.5, 2e4, 1e-3, r);
  for (double tau : {10.0, 30.0, 100.0, 300.0, 1000.0}) EXPECT_NEAR(fb.adev(tau) / 0.664e-6, 1.0, 0.08) << tau;
  EXPECT_LT(fb.adev(0.01), 0.5 * 0.664e-6);  // below tau_min: not flicker any more
}

// The emulated DUT takes a period's interference with fill(): it must give the bits of
// step() called once per loop step, for any number of lines (groups of three, two and one pairs
// and a single line) and any span.
TEST(Noise, LineBandFillEqualsStepBitForBit) {
  for (int lines : {1, 3, 5, 6, 9, 11, 13}) {
    noise::Rng ra(9, 0), rb(9, 0);
    noise::LineBand a(795, 970, lines, 2.0, 1e-3, 10000, 1e-3, ra);
    noise::LineBand b(795, 970, lines, 2.0, 1e-3, 10000, 1e-3, rb);
    std::vector<double> out;
    for (std::size_t n : {10u, 1u, 7u, 10u, 0u, 33u}) {
      a.update_envelopes(ra);
      b.update_envelopes(rb);
      out.assign(n, -1.0);
      a.fill(out);
      for (std::size_t k = 0; k < n; ++k) ASSERT_EQ(out[k], b.step()) << lines << " lines, span " << n << ", k " << k;
    }
  }
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
      "interference_rms_g = 0\npolling_b_g = 0\npolling_k_g_per_rts = 0\noutput_lsb_g = 0\nsense_adc_bits = 30\n";
  toml::table t = cfg::parse_string(text, "quiet.toml");
  cfg::merge_into(t, cfg::parse_string(extra, "test.toml"));
  return EmulatedDut(load_dut_params(&t), seed);
}

// The Allan phase of the shipped procedure, with the paper profile's [analysis] settings.
analysis::NoiseTerms allan_terms(const std::vector<double>& x) {
  static const acceptance::AllanSettings paper = acceptance::allan_settings(acceptance::load_profile("paper"));
  return acceptance::allan_channel_terms(x, paper).terms;
}

analysis::NoiseTerms analyse(EmulatedDut& d, double seconds) {
  std::vector<double> x(static_cast<std::size_t>(seconds * 1000));
  for (double& v : x) {
    double y;
    d.next(v, y);
  }
  return allan_terms(x);
}

std::string describe(const analysis::NoiseTerms& nt) {
  std::ostringstream o;
  o << "fit over tau = " << (nt.model.tau_s.empty() ? 0.0 : nt.model.tau_s.front()) << ".."
    << (nt.model.tau_s.empty() ? 0.0 : nt.model.tau_s.back()) << " s (" << nt.model.dropped_short
    << " short points dropped, chi2/dof " << nt.model.chi2_per_dof << ", model error " << nt.wls.model_error << "):";
  const char* names = "QNBKR";
  int i = 0;
  for (const analysis::Term* t : {&nt.wls.Q, &nt.wls.N, &nt.wls.B, &nt.wls.K, &nt.wls.R}) {
    o << " " << names[i] << " ";
    if (t->value) o << *t->value << " [" << t->lo.value_or(0) << ", " << t->hi.value_or(0) << "]";
    else o << "null";
    o << " (share " << nt.wls.share[static_cast<std::size_t>(i)] << ")";
    ++i;
  }
  o << "; paper B " << nt.B.value.value_or(0) << " at tau_cp " << nt.tau_cp_s.value_or(0);
  return o.str();
}

// true value inside the reported 68 % bounds widened to 2.5 sigma, and within `rel`. About 15
// such checks over the sets: at 2 sigma one would miss by chance in about every second run of
// the suite (QNB's B missed by 0.02 %), at 2.5 sigma in about every fifth.
void expect_found(const analysis::Term& t, double truth, double rel, const char* what) {
  ASSERT_TRUE(t.value.has_value()) << what << ": " << t.reason;
  EXPECT_NEAR(*t.value / truth, 1.0, rel) << what << " = " << *t.value << ", injected " << truth;
  if (t.lo && t.hi) {
    EXPECT_GE(truth, *t.value - 2.5 * (*t.value - *t.lo) - 0.02 * truth) << what;
    EXPECT_LE(truth, *t.value + 2.5 * (*t.hi - *t.value) + 0.02 * truth) << what;
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

// Several parameter sets of injected terms, each term placed so that it dominates the Allan
// curve somewhere in tau <= T/4 (otherwise the method cannot see it, by design). The truths:
// N = d sqrt(5) (white at the 10 kHz loop rate, sample-and-hold at 1 kHz), Q = lsb tau0/sqrt(12)
// (velocity-preserving rounding, dithered), B = flicker_b_g (the bank is scaled to its analytic
// flat level 0.664 B; tau_max 2e4 s keeps it flat over the record), K = rrw_k_g_per_rts or, for
// the 1 kHz pick-up's drift, polling_k_g_per_rts (x sees a unit-norm projection of its I, Q).
struct TermSet {
  const char* name;
  const char* toml;
  double seconds;
  uint64_t seed;
  double q = 0, n = 0, b = 0, k = 0;  // injected truths (0 = not injected), seconds units
  double rel_q = 0.15, rel_n = 0.08, rel_b = 0.35, rel_k = 0.4;
};
void PrintTo(const TermSet& s, std::ostream* os) { *os << s.name; }

class TermRecovery : public ::testing::TestWithParam<TermSet> {};

TEST_P(TermRecovery, FindsEachInjectedTermWithinItsBounds) {
  const TermSet& s = GetParam();
  EmulatedDut d = quiet_dut(std::string("[noise]\nflicker_tau_max_s = 2e4\n") + s.toml, s.seed);
  const analysis::NoiseTerms nt = analyse(d, s.seconds);
  SCOPED_TRACE(describe(nt));
  if (s.q > 0) expect_found(nt.Q, s.q, s.rel_q, "Q");
  if (s.n > 0) expect_found(nt.N, s.n, s.rel_n, "N");
  if (s.b > 0) expect_found(nt.wls.B, s.b, s.rel_b, "B (weighted fit)");
  if (s.k > 0) expect_found(nt.K, s.k, s.rel_k, "K");
  // a term not injected is not reported (Q from the velocity quantiser needs output_lsb_g)
  if (s.k == 0) {
    EXPECT_FALSE(nt.K.value.has_value()) << nt.K.reason;
  }
  EXPECT_FALSE(nt.R.value.has_value()) << "R from " << s.seconds << " s";
}

const double kRt5 = std::sqrt(5.0), kRt12 = std::sqrt(12.0);
INSTANTIATE_TEST_SUITE_P(
    Sets, TermRecovery,
    ::testing::Values(
        // N, B, K: crossovers N/B at 10 s, B/K at 150 s; one hour
        TermSet{"NBK", "sense_white_g_rthz = 1.414e-5\nflicker_b_g = 1.5e-5\nrrw_k_g_per_rts = 1.414e-6\n", 3600, 21,
                0, 1.414e-5 * kRt5, 1.5e-5, 1.414e-6},
        // N and K only (crossover sqrt(3) N / K = 39 s), 20 min
        TermSet{"NK", "sense_white_g_rthz = 2e-5\nrrw_k_g_per_rts = 2e-6\n", 1200, 3, 0, 2e-5 * kRt5, 0, 2e-6},
        // Q, N, B: Q dominates at tau0 only if the white sd < LSB/2, and the white noise must be
        // >= ~0.35 LSB per sample to dither the rounding; N/B crossover at 5 s
        TermSet{"QNB", "sense_white_g_rthz = 3e-4\noutput_lsb_g = 6e-2\nflicker_b_g = 4.5e-4\n", 1200, 4,
                6e-2 * 1e-3 / kRt12, 3e-4 * kRt5, 4.5e-4, 0},
        // K from the drift of the 1 kHz pick-up's envelope, folded to DC by the 1 kHz polling
        TermSet{"NK-polling", "sense_white_g_rthz = 2e-5\npolling_k_g_per_rts = 2e-6\n", 1200, 5, 0, 2e-5 * kRt5, 0,
                2e-6},
        // all four: N/B at 5 s, B/K at 600 s; two hours so that K dominates below T/4. K rests on
        // the last three octave points (EDF < 10), one realisation: within 60 % (measured 1.53x,
        // inside its 2.5-sigma bounds). The loop shapes the shortest taus, the fit starts at 16 ms
        // (goodness of fit), where Q is 12 % of sigma^2: Q 5.5 % high, at 2.5 sigma of its bounds.
        TermSet{"QNBK", "sense_white_g_rthz = 3e-4\noutput_lsb_g = 6e-2\nflicker_b_g = 4.5e-4\nrrw_k_g_per_rts = 2.1e-5\n",
                7200, 6, 6e-2 * 1e-3 / kRt12, 3e-4 * kRt5, 4.5e-4, 2.1e-5, 0.15, 0.08, 0.35, 0.6}),
    [](const ::testing::TestParamInfo<TermSet>& i) {
      std::string n = i.param.name;
      for (char& c : n)
        if (c == '-') c = '_';
      return n;
    });

TEST(NoiseRecovery, FindsBFromFlicker) {
  // B by the paper's method (the quartic's flat segment, sigma(tau_cp) / 0.664), two seeds
  for (uint64_t seed : {5u, 6u}) {
    EmulatedDut d = quiet_dut("[noise]\nsense_white_g_rthz = 1e-6\nflicker_b_g = 2e-5\n", seed);
    const analysis::NoiseTerms nt = analyse(d, 1200);
    ASSERT_TRUE(nt.B.value.has_value()) << nt.B.reason;
    EXPECT_NEAR(*nt.B.value / 2e-5, 1.0, 0.3) << "seed " << seed << " tau_cp " << nt.tau_cp_s.value_or(0);
  }
}

TEST(Noise, GaussMarkovIsARandomWalkOverShortTimes) {
  // ensemble of processes started at 0: variance k^2 t for t << tau, k^2 tau/2 (1 - e^{-2t/tau}) in general
  const double k = 1e-6, tau = 1000, dt = 1e-3;
  noise::Rng r(8, 0);
  const int n = 2000, steps = 20000;  // 20 s
  double s2 = 0;
  for (int j = 0; j < n; ++j) {
    noise::GaussMarkov g(k, tau, dt);
    for (int i = 0; i < steps; ++i) g.step(r);
    s2 += g.value() * g.value();
  }
  const double t = steps * dt, expect = k * k * tau / 2 * (1 - std::exp(-2 * t / tau));
  EXPECT_NEAR(s2 / n / expect, 1.0, 0.1);  // 2000 samples: sd of the estimate 3 %
  EXPECT_NEAR(expect / (k * k * t), 1.0, 0.02);
  noise::GaussMarkov off(0, tau, dt);
  EXPECT_EQ(off.step(r), 0.0);
}

}  // namespace
}  // namespace rig::plant
