#include "analysis/filter.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::analysis {

using cd = std::complex<double>;

std::complex<double> response(const rig::FilterConfig& f, double f_hz) {
  if (!f.enabled) return 1.0;
  const cd z1 = std::polar(1.0, -2 * std::numbers::pi * f_hz / f.rate_hz);  // z^-1
  cd h = 1.0;
  for (const auto& s : f.sections) h *= (s.b0 + s.b1 * z1 + s.b2 * z1 * z1) / (1.0 + s.a1 * z1 + s.a2 * z1 * z1);
  return h;
}

double bandwidth_at_level(const rig::FilterConfig& f, double level) {
  if (!(level > 0 && level < 1)) throw std::invalid_argument("bandwidth_at_level: level must be in (0, 1)");
  const double nyq = f.rate_hz / 2, dc = std::abs(response(f, 0));
  if (dc == 0) throw std::invalid_argument("bandwidth_at_level: filter has zero DC gain");
  auto below = [&](double fr) { return std::abs(response(f, fr)) / dc < level; };
  constexpr int kScan = 20000;
  double lo = 0;
  for (int i = 1; i <= kScan; ++i) {
    const double fr = nyq * i / kScan;
    if (below(fr)) {
      double hi = fr;
      for (int it = 0; it < 60; ++it) {
        const double mid = (lo + hi) / 2;
        (below(mid) ? hi : lo) = mid;
      }
      return (lo + hi) / 2;
    }
    lo = fr;
  }
  return nyq;
}

double settling_time(const rig::FilterConfig& f, double tolerance) {
  if (!(tolerance > 0 && tolerance < 1)) throw std::invalid_argument("settling_time: tolerance must be in (0, 1)");
  const double final_v = std::abs(response(f, 0)) * (std::real(response(f, 0)) < 0 ? -1 : 1);
  if (!f.enabled || f.sections.empty()) return 0;
  // Simulate until the response has stayed inside the band for a long stretch.
  constexpr std::size_t kMax = 10'000'000, kQuiet = 100'000;
  std::vector<double> w1(f.sections.size(), 0), w2(f.sections.size(), 0);
  std::size_t last_out = 0;
  bool ever_out = false;
  for (std::size_t n = 0; n < kMax; ++n) {
    double v = 1.0;
    for (std::size_t k = 0; k < f.sections.size(); ++k) {
      const auto& s = f.sections[k];
      const double y = s.b0 * v + w1[k];
      w1[k] = s.b1 * v - s.a1 * y + w2[k];
      w2[k] = s.b2 * v - s.a2 * y;
      v = y;
    }
    if (std::abs(v - final_v) > tolerance * std::abs(final_v)) {
      last_out = n;
      ever_out = true;
    } else if (n - last_out > kQuiet) {
      break;
    }
  }
  return ever_out ? static_cast<double>(last_out + 1) / f.rate_hz : 0.0;
}

rig::FilterConfig butterworth_lowpass(int order, double fc_hz, double rate_hz) {
  if (order < 1 || order > 4) throw std::invalid_argument("butterworth_lowpass: order must be 1..4, got " + std::to_string(order));
  if (!(rate_hz > 0) || !(fc_hz > 0) || fc_hz >= rate_hz / 2)
    throw std::invalid_argument("butterworth_lowpass: need 0 < fc < rate/2 (fc " + std::to_string(fc_hz) + " Hz, rate " +
                                std::to_string(rate_hz) + " Hz)");
  rig::FilterConfig f;
  f.rate_hz = rate_hz;
  // Prewarped analogue cut-off relative to the bilinear constant: K = tan(pi fc / fs).
  const double K = std::tan(std::numbers::pi * fc_hz / rate_hz);
  // Second-order sections from pole pairs at angles theta_k = pi (2k + order - 1) / (2 order).
  for (int k = 0; k < order / 2; ++k) {
    const double theta = std::numbers::pi * (2.0 * k + 1) / (2.0 * order);
    const double q2 = 2 * std::sin(theta);  // s^2 + q2 s + 1 (normalised)
    const double norm = 1 + q2 * K + K * K;
    rig::Biquad b;
    b.b0 = K * K / norm;
    b.b1 = 2 * b.b0;
    b.b2 = b.b0;
    b.a1 = 2 * (K * K - 1) / norm;
    b.a2 = (1 - q2 * K + K * K) / norm;
    f.sections.push_back(b);
  }
  if (order % 2 == 1) {  // real pole s = -1
    rig::Biquad b;
    b.b0 = K / (1 + K);
    b.b1 = b.b0;
    b.a1 = (K - 1) / (K + 1);
    f.sections.push_back(b);
  }
  return f;
}

rig::FilterConfig paper_wf() {
  rig::FilterConfig f;
  f.rate_hz = 10000.0;
  f.sections.push_back(rig::Biquad{0.148895, 0, 0, -1.228261, 0.377156});
  return f;
}

std::vector<double> apply(const rig::FilterConfig& f, std::span<const double> x) {
  std::vector<double> y(x.begin(), x.end());
  if (!f.enabled) return y;
  for (const auto& s : f.sections) {
    double w1 = 0, w2 = 0;
    for (double& v : y) {
      const double in = v;
      const double out = s.b0 * in + w1;
      w1 = s.b1 * in - s.a1 * out + w2;
      w2 = s.b2 * in - s.a2 * out;
      v = out;
    }
  }
  return y;
}

double rms(std::span<const double> x) {
  if (x.empty()) return 0;
  double s = 0;
  for (double v : x) s += v * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

}  // namespace rig::analysis
