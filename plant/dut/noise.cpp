#include "plant/dut/noise.hpp"

#include <algorithm>
#include <limits>

namespace rig::plant::noise {

BandNoise::BandNoise(double f_lo, double f_hi, double rate_hz, double rms) {
  // RBJ audio-EQ cookbook band-pass, constant 0 dB peak gain.
  const double f0 = std::sqrt(f_lo * f_hi);
  const double w0 = 2 * std::numbers::pi * f0 / rate_hz;
  const double bw_oct = std::log2(f_hi / f_lo);
  const double alpha = std::sin(w0) * std::sinh(std::log(2.0) / 2 * bw_oct * w0 / std::sin(w0));
  const double a0 = 1 + alpha;
  sec_.c = Biquad{alpha / a0, 0, -alpha / a0, -2 * std::cos(w0) / a0, (1 - alpha) / a0};
  // Noise gain = sum of the squared impulse response.
  design::Section probe = sec_;
  double energy = 0;
  for (int i = 0; i < 2000000; ++i) {
    const double h = probe.step(i == 0 ? 1.0 : 0.0);
    energy += h * h;
    if (i > 1000 && std::abs(h) < 1e-12 && std::abs(probe.w1) < 1e-12) break;
  }
  scale_ = energy > 0 ? rms / std::sqrt(energy) : 0;
}

LineBand::LineBand(double f_lo, double f_hi, int lines, double coherence_s, double rms, double rate_hz,
                   double env_dt, Rng& rng) {
  if (rms <= 0 || lines <= 0) return;
  // each line carries rms^2/lines; a complex envelope of per-quadrature variance v gives
  // Re{a e^{jwt}} a variance of v.
  const double sd = rms / std::sqrt(static_cast<double>(lines));
  phi_ = std::exp(-env_dt / coherence_s);
  drive_ = sd * std::sqrt(1 - phi_ * phi_);
  for (int j = 0; j < lines; ++j) {
    const double f = lines == 1 ? (f_lo + f_hi) / 2 : f_lo + (f_hi - f_lo) * j / (lines - 1);
    const double w = 2 * std::numbers::pi * f / rate_hz;
    const double ph = 2 * std::numbers::pi * rng.uniform();
    lines_.push_back(Line{std::cos(ph), std::sin(ph), std::cos(w), std::sin(w), sd * rng.normal(), sd * rng.normal()});
  }
}

void LineBand::update_envelopes(Rng& rng) {
  for (Line& l : lines_) {
    l.ar = phi_ * l.ar + drive_ * rng.normal();
    l.ai = phi_ * l.ai + drive_ * rng.normal();
    const double k = 1.5 - 0.5 * (l.c * l.c + l.s * l.s);  // keep the carrier on the unit circle
    l.c *= k;
    l.s *= k;
  }
}

namespace {
// Allan variance of a Gauss-Markov process of variance s2 and correlation time T
// (continuous white drive q = 2 s2 / T):
// AVAR(tau) = q T^2 / tau * [1 - T/(2 tau) (3 - 4 e^{-tau/T} + e^{-2 tau/T})].
double gm_avar(double s2, double T, double tau) {
  const double x = tau / T;
  double bracket;
  if (x < 1e-3) {
    bracket = x * x / 3;  // series: the random-walk limit
  } else {
    bracket = 1 - (3 - 4 * std::exp(-x) + std::exp(-2 * x)) / (2 * x);
  }
  return 2 * s2 * T / tau * bracket;
}
}  // namespace

FlickerBank::FlickerBank(double b, double tau_min, double tau_max, double dt, Rng& rng) {
  const int decades_x3 = static_cast<int>(std::ceil(3 * std::log10(tau_max / tau_min)));
  const int n = std::max(2, decades_x3 + 1);
  for (int j = 0; j < n; ++j) {
    Proc p{};
    p.tau = tau_min * std::pow(tau_max / tau_min, static_cast<double>(j) / (n - 1));
    p.every = static_cast<uint32_t>(std::max(1.0, std::floor(p.tau / (50 * dt))));
    p.count = 0;
    p.phi = std::exp(-static_cast<double>(p.every) * dt / p.tau);
    procs_.push_back(p);
  }
  // Unit-variance bank: find its flat Allan level inside the covered decades, scale to B.
  double peak = 0;
  for (double lt = std::log10(tau_min) + 0.5; lt <= std::log10(tau_max) - 0.5; lt += 0.02)
    peak = std::max(peak, adev_unit(std::pow(10.0, lt)));
  if (peak <= 0)
    for (double lt = std::log10(tau_min) - 1; lt <= std::log10(tau_max) + 1; lt += 0.02)
      peak = std::max(peak, adev_unit(std::pow(10.0, lt)));
  sd_ = b > 0 && peak > 0 ? 0.664 * b / peak : 0.0;
  sum_ = 0;
  for (auto& p : procs_) {
    p.drive = sd_ * std::sqrt(1 - p.phi * p.phi);
    p.value = sd_ * rng.normal();
    sum_ += p.value;
  }
}

double FlickerBank::adev_unit(double tau) const {
  double v = 0;
  for (const auto& p : procs_) v += gm_avar(1.0, p.tau, tau);
  return std::sqrt(v);
}

double FlickerBank::step(Rng& rng) {
  if (++elapsed_ < due_) return sum_;
  // Some process is due at this step: every count advances by the steps elapsed (none passes
  // its `every`: due_ was the least distance to it), and the due ones draw in bank order, as
  // counting each process every step would.
  bool changed = false;
  uint32_t due = std::numeric_limits<uint32_t>::max();
  for (auto& p : procs_) {
    p.count += elapsed_;
    if (p.count >= p.every) {
      p.count = 0;
      p.value = p.phi * p.value + p.drive * rng.normal();
      changed = true;
    }
    due = std::min(due, p.every - p.count);
  }
  elapsed_ = 0;
  due_ = due;
  if (changed) {  // re-summing (not incrementing) keeps rounding from drifting
    sum_ = 0;
    for (const auto& p : procs_) sum_ += p.value;
  }
  return sum_;
}

}  // namespace rig::plant::noise
