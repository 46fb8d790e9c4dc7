// Injected-noise generator: accelerometer output (g) with known IEEE Std 952 terms, and the
// coverage check of the noise-term fit against them (tests/analysis test_noise_coverage, the
// CI-sized form; bench/analysis coverage_noise, the larger one). Header-only, test code.
//
// Model (IEEE 952 Annex C, tau in s):
//   sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2
// Realisation, per sample n at tau0 = 1/rate:
//   Q  white phase (quantisation): y_n += (e_{n+1} - e_n)/tau0, e ~ N(0, Q^2): the phase is
//      white with variance Q^2, so the second difference gives 3 Q^2/tau^2 exactly.
//   N  white rate: y_n += N/sqrt(tau0) w_n (one-sided S_y = 2 N^2 -> N^2/tau).
//   B  flicker: S_y(f) = h_{-1}/f with 2 ln2 h_{-1} = (2 ln2/pi) B^2, i.e. h_{-1} = B^2/pi, as a
//      sum of Ornstein-Uhlenbeck (AR(1)) processes with corner frequencies f_j spaced 3 per
//      decade from 1/(1000 T) to rate/4: sum_j (c/f_j)/(1 + (f/f_j)^2) = pi c/(2 f ln r) for
//      spacing ratio r, so each process has one-sided level A_j = 2 h ln r/(pi f_j) and
//      variance A_j f_j pi/2 = h ln r (a standard 1/f synthesis; ripple < 1 % at 3/decade).
//   K  rate random walk: y_n += u_n, u_n = u_{n-1} + K sqrt(tau0) w_n (K^2 tau/3).
//   R  rate ramp: y_n += R n tau0 (deterministic; R^2 tau^2/2).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace rig::analysis::injected {

struct Terms {
  double Q = 0, N = 0, B = 0, K = 0, R = 0;  // g*s, g*s^0.5, g, g/s^0.5, g/s
  double at(int k) const { return k == 0 ? Q : k == 1 ? N : k == 2 ? B : k == 3 ? K : R; }
};

// The model's sigma^2 share of term k at tau.
inline double term_avar(const Terms& t, int k, double tau) {
  switch (k) {
    case 0: return 3 * t.Q * t.Q / (tau * tau);
    case 1: return t.N * t.N / tau;
    case 2: return 2 * std::numbers::ln2 / std::numbers::pi * t.B * t.B;
    case 3: return t.K * t.K * tau / 3;
    default: return t.R * t.R * tau * tau / 2;
  }
}
inline double model_avar(const Terms& t, double tau) {
  double s = 0;
  for (int k = 0; k < 5; ++k) s += term_avar(t, k, tau);
  return s;
}

inline std::vector<double> generate(const Terms& t, double rate_hz, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const double tau0 = 1.0 / rate_hz, T = static_cast<double>(n) * tau0;
  std::vector<double> y(n, 0.0);
  if (t.Q > 0) {
    double prev = t.Q * g(rng);
    for (std::size_t i = 0; i < n; ++i) {
      const double e = t.Q * g(rng);
      y[i] += (e - prev) / tau0;
      prev = e;
    }
  }
  if (t.N > 0) {
    const double s = t.N / std::sqrt(tau0);
    for (std::size_t i = 0; i < n; ++i) y[i] += s * g(rng);
  }
  if (t.B > 0) {
    const double h = t.B * t.B / std::numbers::pi, r = std::pow(10.0, 1.0 / 3.0);
    const double var_j = h * std::log(r);
    for (double fc = rate_hz / 4; fc >= 1 / (1000 * T); fc /= r) {
      const double a = std::exp(-2 * std::numbers::pi * fc * tau0), b = std::sqrt(var_j * (1 - a * a));
      double u = std::sqrt(var_j) * g(rng);  // stationary start
      for (std::size_t i = 0; i < n; ++i) {
        u = a * u + b * g(rng);
        y[i] += u;
      }
    }
  }
  if (t.K > 0) {
    const double s = t.K * std::sqrt(tau0);
    double u = 0;
    for (std::size_t i = 0; i < n; ++i) y[i] += (u += s * g(rng));
  }
  if (t.R > 0)
    for (std::size_t i = 0; i < n; ++i) y[i] += t.R * static_cast<double>(i) * tau0;
  return y;
}

}  // namespace rig::analysis::injected
