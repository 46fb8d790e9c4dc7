// Output-filter quality (docs/method.md "Spectral analysis and the output filter"): frequency
// response of cascaded biquads, bandwidth at a level, step-response settling time, RMS,
// Butterworth design (bilinear transform with prewarping) and the paper's W_f(z).
#pragma once
#include <complex>
#include <span>
#include <vector>

#include "rig/core/dut_link.hpp"

namespace rig::analysis {

// H(e^{j 2 pi f / rate}) of the cascade (1 when the filter is disabled).
std::complex<double> response(const rig::FilterConfig& f, double f_hz);
// Lowest frequency where |H(f)| / |H(0)| falls to `level` (0.5 or 1/sqrt(2)); Hz.
// Returns the Nyquist frequency if it never falls that low. Throws std::invalid_argument for level outside (0, 1).
double bandwidth_at_level(const rig::FilterConfig& f, double level);
// Unit-step response settling time: the time after which the output stays within
// tolerance * |final value| of the final value (DC gain); s, at the filter's rate.
double settling_time(const rig::FilterConfig& f, double tolerance = 0.02);
// Butterworth low-pass of order 1..4 (bilinear transform, cut-off prewarped so that
// |H(fc)| = 1/sqrt(2) exactly). Throws std::invalid_argument for a bad order or fc >= rate/2.
rig::FilterConfig butterworth_lowpass(int order, double fc_hz, double rate_hz);
// The paper's W_f(z) = 0.148895 z^2 / (z^2 - 1.228261 z + 0.377156), at 10 kHz.
rig::FilterConfig paper_wf();
// Runs the cascade over x from rest (direct form II transposed).
std::vector<double> apply(const rig::FilterConfig& f, std::span<const double> x);
// sqrt(mean(x^2)), the paper's RMS error criterion.
double rms(std::span<const double> x);

}  // namespace rig::analysis
