#include "analysis/long_tau_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "analysis/edf.hpp"

namespace rig::analysis {

namespace {

// One second difference of the reflected phase at grid centre k, m = j grid steps, as at most
// five (grid index, coefficient) pairs with equal indices merged (SP 1065 eq. 25's reflection:
// x*(-i) = 2 x(0) - x(i), x*(K+i) = 2 x(K) - x(K-i)).
struct Diff {
  std::size_t idx[5];
  double c[5];
  int n = 0;
  void add(std::size_t i, double v) {
    for (int q = 0; q < n; ++q)
      if (idx[q] == i) {
        c[q] += v;
        return;
      }
    idx[n] = i, c[n] = v, ++n;
  }
};

Diff second_difference(std::size_t K, std::size_t k, std::size_t j) {
  Diff d;
  if (k >= j) {
    d.add(k - j, 1);
  } else {
    d.add(0, 2);
    d.add(j - k, -1);
  }
  d.add(k, -2);
  if (k + j <= K) {
    d.add(k + j, 1);
  } else {
    d.add(K, 2);
    d.add(2 * K - k - j, -1);
  }
  return d;
}

// E[D^2] of the second difference d for the power-law phase covariances (unit intensity per
// sample; times in samples = grid index * stride, shifted to the earliest point: D annihilates
// constants and lines, so only the increments after that point matter):
//   white PM  cov(s, t) = [s = t];
//   white FM  x Brownian:            cov(u, v) = min(u, v);
//   RW FM     x the integral of a Brownian y: cov(u, v) = u^2 (3 v - u) / 6, u <= v;
// and for the ramp D itself (x = t^2, deterministic) squared.
std::array<double, 4> expected_sq(const Diff& d, std::size_t stride) {
  std::size_t lo = d.idx[0];
  for (int q = 1; q < d.n; ++q) lo = std::min(lo, d.idx[q]);
  double t[5];
  for (int q = 0; q < d.n; ++q) t[q] = static_cast<double>((d.idx[q] - lo) * stride);
  double wpm = 0, wfm = 0, rw = 0, ramp = 0;
  for (int a = 0; a < d.n; ++a) {
    wpm += d.c[a] * d.c[a];
    ramp += d.c[a] * t[a] * t[a];
    for (int b = 0; b < d.n; ++b) {
      const double u = std::min(t[a], t[b]), v = std::max(t[a], t[b]);
      wfm += d.c[a] * d.c[b] * u;
      rw += d.c[a] * d.c[b] * u * u * (3 * v - u) / 6;
    }
  }
  return {wpm, wfm, rw, ramp * ramp};
}

}  // namespace

double totvar_on_grid(std::span<const double> X, std::size_t j, std::size_t stride, double tau0) {
  const std::size_t K = X.size() - 1;
  double sum = 0;
  for (std::size_t k = 1; k < K; ++k) {
    const double xa = k >= j ? X[k - j] : 2 * X[0] - X[j - k];
    const double xb = k + j <= K ? X[k + j] : 2 * X[K] - X[2 * K - k - j];
    const double d = xa - 2 * X[k] + xb;
    sum += d * d;
  }
  const double tau = static_cast<double>(j * stride) * tau0;
  return sum / (2 * tau * tau * static_cast<double>(K - 1));
}

std::array<double, 5> totvar_factors(std::size_t K, std::size_t j, std::size_t stride) {
  // Interior reference: x(k-j) - 2 x(k) + x(k+j), no reflection (the Allan variance's term).
  Diff in;
  in.add(0, 1), in.add(j, -2), in.add(2 * j, 1);
  const std::array<double, 4> ref = expected_sq(in, stride);
  std::array<double, 4> sum{};
  for (std::size_t k = 1; k < K; ++k) {
    const std::array<double, 4> e = expected_sq(second_difference(K, k, j), stride);
    for (int q = 0; q < 4; ++q) sum[static_cast<std::size_t>(q)] += e[static_cast<std::size_t>(q)];
  }
  const double centres = static_cast<double>(K - 1);
  // Flicker FM: SP 1065 sec. 5.2.11, E[Totvar] = AVAR (1 - a tau/T), a = 1/(3 ln 2) = 0.481.
  const double r = static_cast<double>(j) / static_cast<double>(K);
  return {sum[0] / centres / ref[0], sum[1] / centres / ref[1], 1 - r / (3 * std::numbers::ln2),
          sum[2] / centres / ref[2], sum[3] / centres / ref[3]};
}

std::array<double, 4> totvar_ramp_cross(std::size_t K, std::size_t j, std::size_t stride) {
  // C = sum_a w_a X_a over the grid, w = (1/(tau^2 (K-1))) sum_k D_R(k) c_k (c_k the
  // coefficients of centre k's reflected second difference, D_R(k) = sum c_k t^2, x = t^2).
  // Times in samples (h = stride apart), unit intensities as in expected_sq.
  const double h = static_cast<double>(stride), tau = static_cast<double>(j) * h;
  std::vector<double> w(K + 1, 0.0);
  double e_ramp = 0, e_wpm = 0, e_wfm = 0, e_rw = 0;
  for (std::size_t k = 1; k < K; ++k) {
    const Diff d = second_difference(K, k, j);
    double dr = 0;
    for (int q = 0; q < d.n; ++q) {
      const double t = static_cast<double>(d.idx[q]) * h;
      dr += d.c[q] * t * t;
    }
    for (int q = 0; q < d.n; ++q) w[d.idx[q]] += dr * d.c[q];
    const std::array<double, 4> e = expected_sq(d, stride);
    e_wpm += e[0], e_wfm += e[1], e_rw += e[2], e_ramp += e[3];
  }
  const double norm = 1 / (tau * tau * static_cast<double>(K - 1));
  for (double& v : w) v *= norm;
  const double to_var = norm / 2;  // E[TOTVAR] = mean E[D^2] / (2 tau^2)
  e_wpm *= to_var, e_wfm *= to_var, e_rw *= to_var, e_ramp *= to_var;
  // white PM: sum w^2. White FM (x Brownian): sum over the intervals of h S_i^2, S_i the sum of
  // w from i on (the x(t_a) share every increment before t_a). Random-walk FM (x = int y, y
  // Brownian): sum w_a x(t_a) = int dB(v) G(v), G(v) = int_v W(u) du, W the suffix sum; G is
  // linear on each interval, so var = sum_i h (G_{i-1}^2 + G_{i-1} G_i + G_i^2) / 3.
  double v_wpm = 0, v_wfm = 0, v_rw = 0;
  for (double x : w) v_wpm += x * x;
  std::vector<double> S(K + 2, 0.0), G(K + 1, 0.0);
  for (std::size_t i = K + 1; i-- > 0;) S[i] = S[i + 1] + (i <= K ? w[i] : 0.0);
  for (std::size_t i = 1; i <= K; ++i) v_wfm += h * S[i] * S[i];
  for (std::size_t i = K; i-- > 0;) G[i] = G[i + 1] + h * S[i + 1];
  for (std::size_t i = 1; i <= K; ++i) v_rw += h * (G[i - 1] * G[i - 1] + G[i - 1] * G[i] + G[i] * G[i]) / 3;
  const double n_wpm = v_wpm / (e_ramp * e_wpm), n_wfm = v_wfm / (e_ramp * e_wfm), n_rw = v_rw / (e_ramp * e_rw);
  return {n_wpm, n_wfm, std::sqrt(n_wfm * n_rw), n_rw};
}

double totvar_term_edf(int term, std::size_t n_phase, std::size_t m, const std::array<double, 4>& scale) {
  static const int kAlpha[4] = {0, 0, -1, -2};  // Q takes white FM's (no Table 7 entry for white PM)
  const int k = std::clamp(term, 0, 3);
  return edf_totdev(n_phase, m, kAlpha[k]) * scale[static_cast<std::size_t>(k)];
}

std::vector<LongTauFitPoint> totvar_fit_points(const ChunkSource& src, DataKind kind, double rate_hz) {
  std::vector<LongTauFitPoint> out;
  const std::uint64_t n = src.size();
  const std::uint64_t n_phase = kind == DataKind::Frequency ? n + 1 : n;
  if (n_phase < 16 || !(rate_hz > 0)) return out;
  const double tau0 = 1 / rate_hz;
  const std::size_t m_max = static_cast<std::size_t>((n_phase - 1) / 2);
  const std::size_t stride = std::max<std::size_t>(1, m_max / kTotvarCentresPerM);
  const std::size_t j = m_max / stride;
  const std::size_t K = static_cast<std::size_t>((n_phase - 1) / stride);
  // The phase every stride-th point: X[k] = x_{k stride}. Frequency: block sums of (y - y0)
  // (a constant frequency is a line in the phase, which TOTVAR ignores; removing it keeps the sums
  // well conditioned for an accelerometer's 1 g), four partial sums so the pass vectorises.
  std::vector<double> X(K + 1);
  std::vector<double> buf;
  const double* whole = src.contiguous();
  const std::uint64_t need = kind == DataKind::Frequency ? static_cast<std::uint64_t>(K) * stride : static_cast<std::uint64_t>(K) * stride + 1;
  constexpr std::size_t kChunk = 1u << 16;
  auto view = [&](std::uint64_t pos, std::size_t len) -> const double* {
    if (whole) return whole + pos;
    buf.resize(len);
    if (src.read_at(pos, buf) != len) return nullptr;
    return buf.data();
  };
  if (kind == DataKind::Frequency) {
    const double* first = view(0, 1);
    if (!first) return out;
    const double y0 = *first;
    double acc = 0;       // running phase / tau0 at the current block boundary
    double part[4] = {};  // partial sums of the current block
    std::size_t in_block = 0, k = 0;
    X[0] = 0;
    for (std::uint64_t pos = 0; pos < need;) {
      const std::size_t len = static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, need - pos));
      const double* p = view(pos, len);
      if (!p) return out;
      std::size_t i = 0;
      while (i < len) {
        const std::size_t take = std::min(len - i, stride - in_block);
        std::size_t q = 0;
        for (; q + 4 <= take; q += 4) {
          part[0] += p[i + q] - y0;
          part[1] += p[i + q + 1] - y0;
          part[2] += p[i + q + 2] - y0;
          part[3] += p[i + q + 3] - y0;
        }
        for (; q < take; ++q) part[0] += p[i + q] - y0;
        i += take, in_block += take;
        if (in_block == stride) {
          acc += (part[0] + part[1]) + (part[2] + part[3]);
          part[0] = part[1] = part[2] = part[3] = 0;
          in_block = 0;
          X[++k] = acc * tau0;
        }
      }
      pos += len;
    }
  } else {
    for (std::size_t k = 0; k <= K; ++k) {
      const double* p = view(static_cast<std::uint64_t>(k) * stride, 1);
      if (!p) return out;
      X[k] = *p;
    }
    const double x0 = X[0], slope = (X[K] - X[0]) / static_cast<double>(K);
    for (std::size_t k = 0; k <= K; ++k) X[k] -= x0 + slope * static_cast<double>(k);
  }
  if (!std::all_of(X.begin(), X.end(), [](double v) { return std::isfinite(v); })) return out;
  LongTauFitPoint p;
  p.m = j * stride;
  p.tau_s = static_cast<double>(p.m) * tau0;
  p.stride = stride;
  p.centres = K - 1;
  p.n_phase = K * stride + 1;
  p.var = totvar_on_grid(X, j, stride, tau0);
  p.factor = totvar_factors(K, j, stride);
  p.ramp_cross = totvar_ramp_cross(K, j, stride);
  if (p.var > 0) out.push_back(p);
  return out;
}

std::vector<LongTauFitPoint> totvar_fit_points(std::span<const double> data, DataKind kind, double rate_hz) {
  return totvar_fit_points(SpanSource(data), kind, rate_hz);
}

}  // namespace rig::analysis
