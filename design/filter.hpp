// The output filter W_f(z) (docs/method.md "Spectral analysis and the output filter"), written
// once: the direct-form-II-transposed step every user runs (this module, the emulated DUT's
// output filter and noise shaping, the loop model's regulator), frequency response, a cascade
// run over a sequence, Butterworth design, the paper's W_f(z), and the figures of the paper's
// criterion 2 read off a step response and an amplitude curve.
#pragma once
#include <complex>
#include <span>
#include <vector>

#include "analysis/loop_response.hpp"
#include "rig/core/filter_config.hpp"

namespace rig::design {

// One DF-II-T step of section `s` with state (w1, w2), the form the DUT's MCU uses.
// Inline: the emulated DUT runs it up to twice per loop period.
[[gnu::always_inline]] inline double df2t_step(const Biquad& s, double& w1, double& w2, double in) {
  const double out = s.b0 * in + w1;
  w1 = s.b1 * in - s.a1 * out + w2;
  w2 = s.b2 * in - s.a2 * out;
  return out;
}

// A section with its state, for code that runs a cascade sample by sample.
struct Section {
  Biquad c;
  double w1 = 0, w2 = 0;
  double step(double in) { return df2t_step(c, w1, w2, in); }
};

// H(e^{j 2 pi f / rate}) of the cascade (1 when the filter is disabled).
std::complex<double> response(const FilterConfig& f, double f_hz);
// Runs the cascade over x from rest (1 when disabled: x unchanged).
std::vector<double> apply_filter(const FilterConfig& f, std::span<const double> x);
// Butterworth low-pass of order 1..4 (bilinear transform, cut-off prewarped so that
// |H(fc)| = 1/sqrt(2) exactly). Throws std::invalid_argument for a bad order or fc >= rate/2.
FilterConfig butterworth_lowpass(int order, double fc_hz, double rate_hz);
// The paper's W_f(z) = 0.148895 z^2 / (z^2 - 1.228261 z + 0.377156), at 10 kHz (docs/method.md).
FilterConfig paper_wf();

// Criterion 2 (docs/method.md): bandwidth at the 0.5 level -> f_req, settling time t_рег -> min.
// METHOD does not fix the settling band; the convention here is 5 % of the final value, the
// usual engineering band for t_рег (Besekersky & Popov) and the one the passport has always
// reported. It is the band at which the paper's "about 0.003 s, with and without the filter"
// reads: the default emulated loop settles to 5 % in 3.2 ms with W_f(z) and 2.9 ms without,
// but to 2 % only after 10.0 and 9.7 ms, because its 5 % overshoot decays with the slow
// integrator pole; a 2 % band would measure that tail, not the speed of the loop and filter.
inline constexpr double kSettlingBand = analysis::kStepSettlingBand;  // 0.05, one constant for model and measurement
// First frequency where the amplitude curve `amp` (at ascending `freq`) falls through `level`
// (0.5 for criterion 2, 1/sqrt(2) for -3 dB), interpolated in log-frequency; 0 if it never does.
double bandwidth_at(std::span<const double> freq, std::span<const double> amp, double level);

}  // namespace rig::design
