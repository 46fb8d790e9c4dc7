#include "analysis/loop_response.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "analysis/gost.hpp"

namespace rig::analysis {

std::vector<double> unit_step(std::span<const double> r, std::size_t pre, double amplitude) {
  if (pre == 0 || pre >= r.size()) throw std::invalid_argument("unit_step: needs samples before and after the step");
  if (amplitude == 0 || !std::isfinite(amplitude)) throw std::invalid_argument("unit_step: amplitude must be non-zero");
  const double base = std::accumulate(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(pre), 0.0) /
                      static_cast<double>(pre);
  std::vector<double> h(r.size() - pre);
  for (std::size_t k = 0; k < h.size(); ++k) h[k] = (r[pre + k] - base) / amplitude;
  return h;
}

double final_value(std::span<const double> h, double tail_fraction) {
  if (h.empty()) return 0;
  const auto n = std::clamp<std::size_t>(static_cast<std::size_t>(tail_fraction * static_cast<double>(h.size())), 1,
                                         h.size());
  return std::accumulate(h.end() - static_cast<std::ptrdiff_t>(n), h.end(), 0.0) / static_cast<double>(n);
}

double settling_time(std::span<const double> h, double dt, double final, double band) {
  const double tol = band * std::abs(final);
  for (std::size_t k = h.size(); k-- > 0;)
    if (!(std::abs(h[k] - final) <= tol)) return static_cast<double>(k + 1) * dt;  // a NaN is outside
  return 0;
}

std::vector<double> amplitude_grid(double rate_hz, double step_hz) {
  std::vector<double> f_hz;
  for (double f = step_hz; f <= rate_hz / 2; f += step_hz) f_hz.push_back(f);
  return f_hz;
}

namespace {

// Impulse response of a normalised step: d[k] = h[k] - h[k-1], h[-1] = 0 (it starts from rest).
std::vector<double> impulse_of(std::span<const double> h) {
  std::vector<double> d(h.size());
  for (std::size_t k = 0; k < h.size(); ++k) d[k] = h[k] - (k ? h[k - 1] : 0.0);
  return d;
}

// |H(f)| / |final| at f_hz[0..n) (n <= kLanes) into amp[0..n): H(e^{jw}) = sum d[k] e^{-jwk}, the
// rotation z advanced by one complex multiply per sample. Each frequency's sum is one serial
// chain (z depends on the z before), so one frequency at a time waits on the multiply's
// latency; kLanes frequencies side by side fill the pipeline and share each load of d. The
// operations per frequency are those of std::complex's acc += v z, z *= rot written out, in the
// same order: each value's bits do not depend on which frequencies share its pass.
constexpr std::size_t kLanes = 8;
void amplitudes(std::span<const double> d, double rate_hz, double final, const double* f_hz, std::size_t n,
                double* amp) {
  double rr[kLanes], ri[kLanes], zr[kLanes], zi[kLanes], ar[kLanes], ai[kLanes];
  for (std::size_t j = 0; j < kLanes; ++j) {
    const std::complex<double> rot = std::polar(1.0, -2 * std::numbers::pi * f_hz[std::min(j, n - 1)] / rate_hz);
    rr[j] = rot.real();
    ri[j] = rot.imag();
    zr[j] = 1;
    zi[j] = 0;
    ar[j] = 0;
    ai[j] = 0;
  }
  for (double v : d)
    for (std::size_t j = 0; j < kLanes; ++j) {
      ar[j] += v * zr[j];
      ai[j] += v * zi[j];
      const double nr = zr[j] * rr[j] - zi[j] * ri[j];
      zi[j] = zr[j] * ri[j] + zi[j] * rr[j];
      zr[j] = nr;
    }
  for (std::size_t j = 0; j < n; ++j) amp[j] = std::abs(std::complex<double>(ar[j], ai[j])) / std::abs(final);
}

std::vector<double> amplitudes(std::span<const double> d, double rate_hz, double final, std::span<const double> f_hz) {
  std::vector<double> amp(f_hz.size());
  for (std::size_t f0 = 0; f0 < f_hz.size(); f0 += kLanes)
    amplitudes(d, rate_hz, final, f_hz.data() + f0, std::min(kLanes, f_hz.size() - f0), amp.data() + f0);
  return amp;
}

}  // namespace

AmplitudeCurve step_amplitude_response(std::span<const double> h, double rate_hz, double final, double step_hz) {
  AmplitudeCurve c;
  if (h.empty() || final == 0) return c;
  c.f_hz = amplitude_grid(rate_hz, step_hz);
  c.amp = amplitudes(impulse_of(h), rate_hz, final, c.f_hz);
  return c;
}

AmplitudeCurve step_amplitude_at(std::span<const double> h, double rate_hz, double final, std::span<const double> f_hz) {
  AmplitudeCurve c;
  if (h.empty() || final == 0) return c;
  c.f_hz.assign(f_hz.begin(), f_hz.end());
  c.amp = amplitudes(impulse_of(h), rate_hz, final, f_hz);
  return c;
}

double step_crossing_frequency(std::span<const double> h, double rate_hz, double final, double level, double step_hz) {
  if (h.empty() || final == 0) return 0;
  // The grid ascending, kLanes points a pass, until the first pair that crosses: the points a
  // crossing_frequency over the whole curve would read, with the same values.
  const std::vector<double> d = impulse_of(h), f = amplitude_grid(rate_hz, step_hz);
  std::vector<double> amp(f.size());
  for (std::size_t f0 = 0; f0 < f.size(); f0 += kLanes) {
    const std::size_t n = std::min(kLanes, f.size() - f0);
    amplitudes(d, rate_hz, final, f.data() + f0, n, amp.data() + f0);
    const std::size_t from = f0 == 0 ? 0 : f0 - 1;
    const double x = crossing_frequency(std::span(f).subspan(from, f0 + n - from),
                                        std::span(amp).subspan(from, f0 + n - from), level);
    if (x != 0) return x;
  }
  return 0;
}

double crossing_frequency(std::span<const double> f_hz, std::span<const double> amp, double level) {
  for (std::size_t k = 1; k < f_hz.size() && k < amp.size(); ++k)
    if (amp[k] < level && amp[k - 1] >= level) {
      const double a = (amp[k - 1] - level) / (amp[k - 1] - amp[k]);
      return std::exp(std::log(f_hz[k - 1]) + a * (std::log(f_hz[k]) - std::log(f_hz[k - 1])));
    }
  return 0;
}

StepFigures step_figures(std::span<const double> h, double rate_hz, double band) {
  StepFigures f = step_figures(h, rate_hz, band, {});
  f.amplitude = step_amplitude_response(h, rate_hz, f.final_value);
  return f;
}

StepFigures step_figures(std::span<const double> h, double rate_hz, double band, std::span<const double> curve_f_hz) {
  StepFigures f;
  f.final_value = final_value(h);
  f.settling_time_s = settling_time(h, 1.0 / rate_hz, f.final_value, band);
  f.amplitude = step_amplitude_at(h, rate_hz, f.final_value, curve_f_hz);
  f.bandwidth_0p5_hz = step_crossing_frequency(h, rate_hz, f.final_value, 0.5);
  if (!h.empty() && f.final_value != 0)
    f.overshoot = std::max(0.0, *std::max_element(h.begin(), h.end()) / f.final_value - 1);
  return f;
}

RepeatedFigure repeated_figure(std::span<const double> v, double resolution) {
  if (v.empty()) throw std::invalid_argument("repeated_figure: no steps");
  RepeatedFigure r;
  r.n = v.size();
  r.value = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(r.n);
  double student = 0;
  if (r.n >= 2) {
    const GostSummary g = gost_summary(v, 0.95);
    r.sd = g.sd;
    student = g.ci_half;
  }
  const double half = std::hypot(student, resolution / 2);
  r.lo = r.value - half;
  r.hi = r.value + half;
  return r;
}

}  // namespace rig::analysis
