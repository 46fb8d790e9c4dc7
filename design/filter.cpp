#include "design/filter.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::design {

std::complex<double> response(const FilterConfig& f, double f_hz) {
  std::complex<double> h = 1.0;
  if (!f.enabled) return h;
  const std::complex<double> z1 = std::polar(1.0, -2 * std::numbers::pi * f_hz / f.rate_hz);  // z^-1
  for (const Biquad& s : f.sections) h *= (s.b0 + s.b1 * z1 + s.b2 * z1 * z1) / (1.0 + s.a1 * z1 + s.a2 * z1 * z1);
  return h;
}

std::vector<double> apply_filter(const FilterConfig& f, std::span<const double> x) {
  std::vector<double> y(x.begin(), x.end());
  if (!f.enabled) return y;
  for (const Biquad& s : f.sections) {
    double w1 = 0, w2 = 0;
    for (double& v : y) v = df2t_step(s, w1, w2, v);
  }
  return y;
}

FilterConfig butterworth_lowpass(int order, double fc_hz, double rate_hz) {
  if (order < 1 || order > 4) throw std::invalid_argument("butterworth_lowpass: order must be 1..4, got " + std::to_string(order));
  if (!(rate_hz > 0) || !(fc_hz > 0) || fc_hz >= rate_hz / 2)
    throw std::invalid_argument("butterworth_lowpass: need 0 < fc < rate/2 (fc " + std::to_string(fc_hz) + " Hz, rate " +
                                std::to_string(rate_hz) + " Hz)");
  FilterConfig f;
  f.rate_hz = rate_hz;
  // Prewarped analogue cut-off relative to the bilinear constant: K = tan(pi fc / fs).
  const double K = std::tan(std::numbers::pi * fc_hz / rate_hz);
  // Second-order sections from pole pairs at angles theta_k = pi (2k + order - 1) / (2 order).
  for (int k = 0; k < order / 2; ++k) {
    const double theta = std::numbers::pi * (2.0 * k + 1) / (2.0 * order);
    const double q2 = 2 * std::sin(theta);  // s^2 + q2 s + 1 (normalised)
    const double norm = 1 + q2 * K + K * K;
    Biquad b;
    b.b0 = K * K / norm;
    b.b1 = 2 * b.b0;
    b.b2 = b.b0;
    b.a1 = 2 * (K * K - 1) / norm;
    b.a2 = (1 - q2 * K + K * K) / norm;
    f.sections.push_back(b);
  }
  if (order % 2 == 1) {  // real pole s = -1
    Biquad b;
    b.b0 = K / (1 + K);
    b.b1 = b.b0;
    b.a1 = (K - 1) / (K + 1);
    f.sections.push_back(b);
  }
  return f;
}

FilterConfig paper_wf() {
  FilterConfig f;
  f.rate_hz = 10000.0;
  f.sections = {Biquad{0.148895, 0, 0, -1.228261, 0.377156}};
  return f;
}

double bandwidth_at(std::span<const double> freq, std::span<const double> amp, double level) {
  return analysis::crossing_frequency(freq, amp, level);
}

}  // namespace rig::design
