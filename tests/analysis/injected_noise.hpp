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
//      sum of Ornstein-Uhlenbeck processes with corner frequencies f_j spaced 3 per decade from
//      30 rate down to 1/(1000 T): sum_j (c/f_j)/(1 + (f/f_j)^2) = pi c/(2 f ln r) for spacing
//      ratio r, so each process has one-sided level A_j = 2 h ln r/(pi f_j) and variance
//      A_j f_j pi/2 = h ln r (a standard 1/f synthesis; ripple < 1 % at 3/decade). Each sample is
//      the process's exact mean over its tau0 (the record is a frequency averaged over each
//      sample, as the Allan estimators take it), drawn jointly with the process's next value
//      (flicker_into), and the bank reaches far above the Nyquist frequency: the point-sampled
//      bank stopping at rate/4 it replaces (2026-12-04) read 3.8 % high at tau0 (aliasing) and
//      5 % low at 2-4 tau0 (the missing top decade). Its expected Allan variance is now the
//      nominal to 2e-5 from tau0 to 256 tau0 and 5.4e-4 below at T/4 (flicker_bank_avar), and
//      simulated records agree within their sampling error (0.05-0.2 % over 100 records).
//   K  rate random walk: y_n += u_n, u_n = u_{n-1} + K sqrt(tau0) w_n (K^2 tau/3).
//   R  rate ramp: y_n += R n tau0 (deterministic; R^2 tau^2/2).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include <boost/random/normal_distribution.hpp>

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

// The flicker bank for coefficient B at rate_hz over a record of T s: each process's corner
// frequency, the processes' common stationary variance v (one-sided level 2 v/(pi f_j), summing to
// h_{-1}/f with h_{-1} = v/ln r), and the summed variance of the per-sample means of the
// processes above 30 rate (run as one white draw: flicker_into).
struct FlickerBank {
  std::vector<double> fc;
  double v = 0, tail = 0;
};

// x - 1 + exp(-x), by its series where the closed form cancels: an Ornstein-Uhlenbeck process of
// rate lambda and stationary variance v integrates over t to a variance 2 v g(lambda t)/lambda^2.
inline double ou_integral_g(double x) {
  return x < 1e-3 ? x * x * (0.5 - x / 6 + x * x / 24) : x + std::expm1(-x);
}

inline FlickerBank flicker_bank(double B, double rate_hz, double T) {
  FlickerBank b;
  const double h = 1.0 / rate_hz, r = std::pow(10.0, 1.0 / 3.0), f_top = 30 * rate_hz;
  b.v = B * B / std::numbers::pi * std::log(r);
  for (double fc = f_top * r;; fc *= r) {
    const double x = 2 * std::numbers::pi * fc * h;
    if (x >= 1e12) break;
    b.tail += 2 * b.v * ou_integral_g(x) / (x * x);  // the variance of its mean over h
  }
  for (double fc = f_top; fc >= 1 / (1000 * T); fc /= r) b.fc.push_back(fc);
  return b;
}

// The bank's expected Allan variance at tau = m tau0, as flicker_into realises it: per process
// (4 V(tau) - V(2 tau))/(2 tau^2) with V(t) = 2 v (lambda t - 1 + exp(-lambda t))/lambda^2 the
// variance of its integral over t, plus the white tail's tail/m. A check of the bank's design
// (its extent and tail) against (2 ln2/pi) B^2 that needs no simulation.
inline double flicker_bank_avar(const FlickerBank& b, double rate_hz, std::size_t m) {
  const double tau = static_cast<double>(m) / rate_hz;
  double avar = b.tail / static_cast<double>(m);
  for (const double fc : b.fc) {
    const double lam = 2 * std::numbers::pi * fc;
    const auto V = [&](double t) { return 2 * b.v * ou_integral_g(lam * t) / (lam * lam); };
    avar += (4 * V(tau) - V(2 * tau)) / (2 * tau * tau);
  }
  return avar;
}

// Adds flicker of coefficient B to y (samples at rate_hz; the record is y.size() samples long):
// the bank above, each sample the exact mean of each process over its interval. For a process of
// rate lambda = 2 pi f_j, stationary variance v and step h = tau0, x = lambda h, a = exp(-x), the
// next value and the integral over the step given the value u:
//   u' = a u + e,  I = u (1 - a)/lambda + eta,  with (e, eta) normal, zero mean,
//   var e = v (1 - a^2),  cov(e, eta) = v (1 - a)^2/lambda,
//   var eta = (2 v/lambda) [h - 2 (1 - a)/lambda + (1 - a^2)/(2 lambda)]
// (the Ito integrals of exp(-lambda (h - s)) and (1 - exp(-lambda (h - s)))/lambda against the
// drive sqrt(2 lambda v) dW). The processes above 30 rate are not run: the mean of each over a
// step is white to within 1/(2 x) < 0.3 % (its stationary variance 2 v (x - 1 + a)/x^2), and
// their sum is one white draw of that summed variance; without it the bank reads 0.5 % low at
// tau0 (it acts as a missing white FM). Being means over tau0, the samples' spectrum falls below
// h_{-1}/f near the Nyquist frequency (to 0.8 of it in the top octave), as any averaged record's
// does: a B read from a PSD there reads low. Draws from Boost's ziggurat normal: the bank takes
// two per process and sample, and the ziggurat is cheaper per draw than std::normal_distribution's
// polar method (2.3x, a review's measurement).
template <class Rng>
void flicker_into(std::vector<double>& y, double B, double rate_hz, Rng& rng) {
  boost::random::normal_distribution<double> g(0.0, 1.0);
  const double h = 1.0 / rate_hz;
  const FlickerBank bank = flicker_bank(B, rate_hz, static_cast<double>(y.size()) * h);
  const double v = bank.v, s_tail = std::sqrt(bank.tail);
  for (double& yi : y) yi += s_tail * g(rng);
  for (const double fc : bank.fc) {
    const double lam = 2 * std::numbers::pi * fc, x = lam * h, a = std::exp(-x);
    const double one_a = -std::expm1(-x);  // 1 - a without cancellation
    // [h - 2 (1 - a)/lambda + (1 - a^2)/(2 lambda)]/h = x^2/3 - x^3/4 + 7 x^4/60 - ... (series
    // below x = 1e-2, where the closed form cancels)
    const double bracket = x < 1e-2 ? x * x * (1.0 / 3 - x / 4 + 7 * x * x / 60)
                                    : 1 - 2 * one_a / x - std::expm1(-2 * x) / (2 * x);
    const double ve = v * one_a * (1 + a), c = v * one_a * one_a / lam, veta = 2 * v / lam * h * bracket;
    const double se = std::sqrt(ve), k = c / se, rest = std::sqrt(std::max(0.0, veta - k * k));
    const double carry = one_a / x;  // (1 - a)/(lambda h)
    double u = std::sqrt(v) * g(rng);  // stationary start
    for (double& yi : y) {
      const double z1 = g(rng), z2 = g(rng);
      yi += u * carry + (k * z1 + rest * z2) / h;
      u = a * u + se * z1;
    }
  }
}

inline std::vector<double> generate(const Terms& t, double rate_hz, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const double tau0 = 1.0 / rate_hz;
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
  if (t.B > 0) flicker_into(y, t.B, rate_hz, rng);
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
