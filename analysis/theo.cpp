// Long-tau statistics (theo.hpp): Theo1, TheoH, MTOT, TTOT, HTOT with their EDFs.
#include "analysis/theo.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "analysis/edf.hpp"
#include "analysis/parallel.hpp"

namespace rig::analysis {

const char* to_string(LongTau s) {
  switch (s) {
    case LongTau::Theo1: return "theo1";
    case LongTau::TheoH: return "theoh";
    case LongTau::MTOT: return "mtot";
    case LongTau::TTOT: return "ttot";
    case LongTau::HTOT: return "htot";
  }
  return "?";
}

std::optional<LongTau> parse_long_tau(const std::string& s) {
  for (LongTau t : {LongTau::Theo1, LongTau::TheoH, LongTau::MTOT, LongTau::TTOT, LongTau::HTOT})
    if (s == to_string(t)) return t;
  return std::nullopt;
}

std::vector<double> detrended_phase(std::span<const double> data, DataKind kind, double rate_hz) {
  const double tau0 = 1.0 / rate_hz;
  std::vector<double> x;
  if (kind == DataKind::Frequency) {
    // x_k = tau0 sum_{j<k} (y_j - ybar): the phase less its end-point line (the line's slope is ybar).
    long double mean = 0;
    for (double v : data) mean += v;
    mean /= static_cast<long double>(std::max<std::size_t>(1, data.size()));
    x.resize(data.size() + 1);
    long double acc = 0;
    x[0] = 0;
    for (std::size_t k = 0; k < data.size(); ++k) {
      acc += (static_cast<long double>(data[k]) - mean) * tau0;
      x[k + 1] = static_cast<double>(acc);
    }
  } else {
    x.assign(data.begin(), data.end());
    if (x.size() >= 2) {
      const long double a = x.front(), b = (static_cast<long double>(x.back()) - a) / (x.size() - 1);
      for (std::size_t k = 0; k < x.size(); ++k) x[k] = static_cast<double>(x[k] - a - b * static_cast<long double>(k));
    }
  }
  return x;
}

namespace {

// Starts 0, stride, 2 stride, ... below `count`: how many.
std::size_t starts(std::size_t count, std::size_t stride) { return count == 0 ? 0 : (count - 1) / stride + 1; }

// The stride keeping count/stride * per_start under the cap, with at least kMinStarts starts.
std::size_t stride_for(std::size_t count, double per_start, double cap) {
  if (count == 0) return 1;
  const double allowed = std::max(static_cast<double>(kMinStarts), cap / std::max(1.0, per_start));
  if (static_cast<double>(count) <= allowed) return 1;
  return static_cast<std::size_t>(std::ceil(static_cast<double>(count) / allowed));
}

}  // namespace

VarSum theo1_var(std::span<const double> x, std::size_t m, double tau0, std::size_t stride) {
  const std::size_t n = x.size();
  if (m < 2 || m % 2 != 0 || m >= n) throw std::invalid_argument("theo1: m must be even and 2 <= m <= N-1");
  const std::size_t h = m / 2;
  std::vector<double> w(h);  // w[k-1] = 1/k, k = m/2 - delta
  for (std::size_t k = 1; k <= h; ++k) w[k - 1] = 1.0 / static_cast<double>(k);
  long double total = 0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < n - m; i += stride, ++used) {
    // With k = h - delta: the bracket is (x_i + x_{i+m}) - (x_{i+k} + x_{i+m-k}), k = 1..h.
    const double a = x[i] + x[i + m];
    const double* lo = x.data() + i;
    const double* hi = x.data() + i + m;
    double s = 0;
#pragma omp simd reduction(+ : s)
    for (std::size_t k = 1; k <= h; ++k) {
      const double d = a - lo[k] - hi[-static_cast<std::ptrdiff_t>(k)];
      s += w[k - 1] * d * d;
    }
    total += s;
  }
  const double mt = static_cast<double>(m) * tau0;
  return {static_cast<double>(total) / (0.75 * static_cast<double>(used) * mt * mt), used * h};
}

namespace {

// One total-variance subsequence: `seq` (3m values) has its linear trend (from the half means)
// removed, is reflected to 9m values (reversed, itself, reversed), and the 6m second
// differences of m-point sums of that are squared and summed. Returns the sum of
// [S_j - 2 S_{j+m} + S_{j+2m}]^2 over j < 6m, S the m-point sums; `buf` is scratch.
double reflected_second_differences(const double* seq, std::size_t m, std::vector<double>& buf) {
  const std::size_t L = 3 * m;
  const std::size_t h1 = L / 2, h2 = (L + 1) / 2;  // first half [0, h1), second half [h2, L)
  double s1 = 0, s2 = 0;
  for (std::size_t j = 0; j < h1; ++j) s1 += seq[j];
  for (std::size_t j = h2; j < L; ++j) s2 += seq[j];
  const double mean1 = s1 / static_cast<double>(h1), mean2 = s2 / static_cast<double>(L - h2);
  // Spacing of the half means: 3m/2 for even 3m, (3m-1)/2 + 1 for odd (the middle point is in neither).
  const double spacing = (L % 2 == 0) ? static_cast<double>(L) / 2 : static_cast<double>((L - 1) / 2 + 1);
  const double slope = (mean2 - mean1) / spacing;
  // Centre on the subsequence (a constant does not change a second difference; it keeps the
  // prefix sums small).
  double centre = 0;
  for (std::size_t j = 0; j < L; ++j) centre += seq[j] - slope * static_cast<double>(j);
  centre /= static_cast<double>(L);
  // Prefix sums P of the 9m extended sequence: P[k] = sum_{j<k} e_j.
  buf.resize(9 * m + 1);
  double* P = buf.data();
  P[0] = 0;
  auto v = [&](std::size_t j) { return seq[j] - slope * static_cast<double>(j) - centre; };
  std::size_t k = 0;
  for (std::size_t j = L; j-- > 0; ++k) P[k + 1] = P[k] + v(j);
  for (std::size_t j = 0; j < L; ++j, ++k) P[k + 1] = P[k] + v(j);
  for (std::size_t j = L; j-- > 0; ++k) P[k + 1] = P[k] + v(j);
  // S_j = P[j+m] - P[j]; S_j - 2 S_{j+m} + S_{j+2m} = P[j+3m] - 3 P[j+2m] + 3 P[j+m] - P[j].
  double s = 0;
  const std::size_t six = 6 * m;
#pragma omp simd reduction(+ : s)
  for (std::size_t j = 0; j < six; ++j) {
    const double d = P[j + 3 * m] - 3 * P[j + 2 * m] + 3 * P[j + m] - P[j];
    s += d * d;
  }
  return s;
}

}  // namespace

VarSum mtot_var(std::span<const double> x, std::size_t m, double tau0, std::size_t stride) {
  const std::size_t n = x.size();
  if (m < 1 || 3 * m > n) throw std::invalid_argument("mtot: m must be in 1..N/3");
  const std::size_t count = n - 3 * m + 1;
  std::vector<double> buf;
  long double total = 0;
  std::size_t used = 0;
  const double mm = static_cast<double>(m);
  for (std::size_t i = 0; i < count; i += stride, ++used)
    total += reflected_second_differences(x.data() + i, m, buf) / (mm * mm) / (6 * mm);
  const double mt = mm * tau0;
  return {static_cast<double>(total) / (2 * mt * mt * static_cast<double>(used)), used * 6 * m};
}

VarSum htot_var(std::span<const double> x, std::size_t m, double tau0, std::size_t stride) {
  if (x.size() < 2) throw std::invalid_argument("htot: needs 2 phase points");
  const std::size_t nf = x.size() - 1;
  if (m < 2 || 3 * m > nf) throw std::invalid_argument("htot: m must be in 2..(N-1)/3");
  std::vector<double> y(nf);
  for (std::size_t k = 0; k < nf; ++k) y[k] = (x[k + 1] - x[k]) / tau0;
  const std::size_t count = nf - 3 * m + 1;
  std::vector<double> buf;
  long double total = 0;
  std::size_t used = 0;
  const double mm = static_cast<double>(m);
  // On frequency values the m-sums' second difference is m times that of the m-averages.
  for (std::size_t i = 0; i < count; i += stride, ++used)
    total += reflected_second_differences(y.data() + i, m, buf) / (mm * mm) / (6 * mm) / 6;
  return {static_cast<double>(total) / static_cast<double>(used), used * 6 * m};
}

double edf_theo1(int alpha, std::size_t n_phase, std::size_t m) {
  const double N = static_cast<double>(n_phase), r = 0.75 * static_cast<double>(m);
  switch (std::clamp(alpha, -2, 2)) {
    case 2: return 0.86 * (N + 1) * (N - 4.0 / 3.0 * r) / (N - r) * (r / (r + 1.14));
    case 1: return (4.798 * N * N - 6.374 * N * r + 12.387 * r) / (std::sqrt(r + 36.6) * (N - r)) * (r / (r + 0.3));
    case 0: {
      const double r15 = std::pow(r, 1.5);
      return ((4.1 * N + 0.8) / r - (3.1 * N + 6.5) / N) * (r15 / (r15 + 5.2));
    }
    case -1: return (2 * N * N - 1.3 * N * r - 3.5 * r) / (N * r) * (r * r * r / (r * r * r + 2.3));
    default: {
      const double a = 4.4 * N;
      return (a - 2) / (2.9 * r) * ((a - 1) * (a - 1) - 8.6 * r * (a - 1) + 11.4 * r * r) / ((a - 3) * (a - 3));
    }
  }
}

double edf_mtot(int alpha, std::size_t n_phase, std::size_t m) {
  // Table 8 holds for m > 8 (Howe's fit; Stable32's note); below, MTOT's few reflected terms
  // behave as MVAR's, whose Greenhall-Riley EDF Stable32's MTOT bounds follow (to 1 %,
  // tests/analysis/test_theo.cpp, Stable32Tot).
  if (m <= 8) return edf_greenhall(std::clamp(alpha, -2, 2), 2, m, n_phase, true, true);
  static constexpr double b[5] = {2.16, 1.73, 1.33, 0.92, 0.79}, c[5] = {2.28, 2.99, 1.89, 0.76, 0.37};
  const auto i = static_cast<std::size_t>(2 - std::clamp(alpha, -2, 2));
  return b[i] * (static_cast<double>(n_phase) / static_cast<double>(m)) - c[i];
}

double edf_htot(int alpha, std::size_t n_phase, std::size_t m) {
  // Table 9 holds for m > 16 and FM noise; elsewhere the overlapping Hadamard EDF
  // (Greenhall-Riley), which is below Stable32's HTOT EDF there (wider bounds, the safe side).
  if (alpha > 0 || m <= 16) return edf_greenhall(std::clamp(alpha, -4, 2), 3, m, n_phase, true, false);
  static constexpr double b0[5] = {0.559, 0.868, 0.938, 0.974, 1.276}, b1[5] = {1.004, 1.140, 1.696, 2.554, 3.149};
  const auto i = static_cast<std::size_t>(-std::max(alpha, -4));
  const double r = static_cast<double>(n_phase) / static_cast<double>(m);
  return r / (b0[i] + b1[i] / r);
}

double tot_bias(LongTau s, int alpha) {
  if (s == LongTau::MTOT || s == LongTau::TTOT) {
    static constexpr double a[5] = {0.94, 0.83, 0.73, 0.70, 0.69};
    return a[static_cast<std::size_t>(2 - std::clamp(alpha, -2, 2))];
  }
  if (s == LongTau::HTOT) {
    if (alpha > 0) return 1.0;
    static constexpr double a[5] = {0.995, 0.851, 0.771, 0.717, 0.679};
    return a[static_cast<std::size_t>(-std::max(alpha, -4))];
  }
  return 1.0;
}

int alpha_at(std::span<const DevPoint> ref, double tau_s) {
  // edf_alpha: the type OADEV's own bounds use, i.e. after the EDF guard (a PM reading at the
  // last OADEV taus of an FM curve must not carry over to the longer taus here).
  if (ref.empty()) return 0;
  int a = ref.front().edf_alpha;
  for (const DevPoint& p : ref)
    if (p.tau_s <= tau_s * (1 + 1e-12)) a = p.edf_alpha;
  return a;
}

namespace {

void validate(std::span<const double> data, const LongTauOptions& o) {
  if (!(o.rate_hz > 0) || !std::isfinite(o.rate_hz))
    throw std::invalid_argument("long-tau: rate must be a positive number of Hz, got " + std::to_string(o.rate_hz));
  if (o.bounds && !(o.confidence > 0 && o.confidence < 1))
    throw std::invalid_argument("long-tau: confidence must be in (0, 1), got " + std::to_string(o.confidence));
  if (const auto bad = first_unusable(data))
    throw std::invalid_argument("long-tau: value " + std::to_string(*bad) + " is not finite or beyond +-2^333");
  if (!(o.max_terms_per_tau > 0)) throw std::invalid_argument("long-tau: max_terms_per_tau must be positive");
}

// The grid's factors for a statistic whose largest m is `top` (Theo1: even m only).
std::vector<std::size_t> grid(const LongTauOptions& o, std::size_t top, bool even, std::size_t bottom) {
  std::vector<std::size_t> m;
  if (!o.factors.empty()) {
    for (std::size_t f : o.factors)
      if (f < bottom || f > top || (even && f % 2 != 0))
        throw std::invalid_argument("long-tau: averaging factor " + std::to_string(f) + " is out of range for " +
                                    to_string(o.type) + " (" + std::to_string(bottom) + ".." + std::to_string(top) +
                                    (even ? ", even)" : ")"));
    return o.factors;
  }
  // The existing grids over [1, top]: tau_factors takes a deviation and a phase count; TOTDEV's
  // largest factor is (N-1)/2, so 2 top + 1 points give `top`.
  for (std::size_t f : tau_factors(o.taus, Deviation::TOTDEV, 2 * top + 1)) {
    if (even && f % 2) f += 1;
    if (f >= bottom && f <= top) m.push_back(f);
  }
  std::sort(m.begin(), m.end());
  m.erase(std::unique(m.begin(), m.end()), m.end());
  return m;
}

// The chi-square interval at the point's EDF, where it is one: a positive EDF whose interval holds
// the value (lo <= dev <= hi). Else none (NaN), with why: the table formulas (SP 1065 Tables 9-11)
// are fits that leave their range at the longest factors.
void set_bounds(LongTauPoint& p, double confidence) {
  const auto [lo, hi] = chi2_bounds(p.dev, p.edf, confidence);
  if (p.edf > 0 && std::isfinite(p.edf) && lo <= p.dev && p.dev <= hi) {
    p.lo = lo;
    p.hi = hi;
    return;
  }
  char why[160];
  if (p.edf > 0)
    std::snprintf(why, sizeof why,
                  "no equal-tail chi-square interval at EDF %.3g (alpha %d) and this confidence holds the value",
                  p.edf, p.alpha);
  else
    std::snprintf(why, sizeof why, "the table EDF for alpha %d is not positive here (%.3g)", p.alpha, p.edf);
  p.bounds_note = why;
  p.lo = p.hi = p.edf = std::numeric_limits<double>::quiet_NaN();
}

unsigned thread_count(unsigned t) { return t ? t : std::max(1u, std::thread::hardware_concurrency()); }

// Theo1 points at the given even factors (shared by Theo1 and TheoH).
std::vector<LongTauPoint> theo1_points(const std::vector<double>& x, const std::vector<std::size_t>& ms,
                                       const LongTauOptions& o, std::span<const DevPoint> ref) {
  const std::size_t n = x.size();
  const double tau0 = 1.0 / o.rate_hz;
  std::vector<LongTauPoint> out(ms.size());
  detail::parallel_for(ms.size(), thread_count(o.threads), [&](std::size_t q) {
    if (o.poll) o.poll();
    const std::size_t m = ms[q];
    LongTauPoint& p = out[q];
    p.m = m;
    p.tau_s = 0.75 * static_cast<double>(m) * tau0;
    p.stride = stride_for(n - m, static_cast<double>(m / 2), o.max_terms_per_tau);
    const VarSum v = theo1_var(x, m, tau0, p.stride);
    p.n_terms = v.terms;
    p.dev = p.dev_raw = std::sqrt(v.var);
    p.estimator = "theo1";
    if (!o.bounds) return;
    p.alpha = std::clamp(o.fixed_alpha.value_or(alpha_at(ref, p.tau_s)), -2, 2);
    p.edf = edf_theo1(p.alpha, n, m);
    // A strided sum holds no more independent information than its starts.
    if (p.stride > 1) p.edf = std::min(p.edf, static_cast<double>(starts(n - m, p.stride)));
    set_bounds(p, o.confidence);
  });
  return out;
}

std::vector<LongTauPoint> tot_points(const std::vector<double>& x, const LongTauOptions& o,
                                     std::span<const DevPoint> ref) {
  const std::size_t n = x.size();
  const double tau0 = 1.0 / o.rate_hz;
  const bool htot = o.type == LongTau::HTOT;
  const std::size_t top = htot ? (n - 1) / 3 : n / 3;
  const std::vector<std::size_t> ms = grid(o, top, false, 1);
  std::vector<LongTauPoint> out(ms.size());
  detail::parallel_for(ms.size(), thread_count(o.threads), [&](std::size_t q) {
    if (o.poll) o.poll();
    const std::size_t m = ms[q];
    LongTauPoint& p = out[q];
    p.m = m;
    p.tau_s = static_cast<double>(m) * tau0;
    p.estimator = to_string(o.type);
    double var = 0;
    std::size_t count = 0;
    if (htot && m == 1) {
      // SP 1065 sec. 5.2.14 / Stable32: the overlapping Hadamard variance at m = 1.
      DevOptions h;
      h.type = Deviation::OHDEV;
      h.data = DataKind::Phase;
      h.rate_hz = o.rate_hz;
      h.factors = {1};
      h.bounds = false;
      h.threads = 1;
      const DevPoint d = deviation(x, h).at(0);
      var = d.dev * d.dev;
      p.n_terms = d.n_terms;
      count = d.n_terms;
    } else {
      count = (htot ? n - 1 : n) - 3 * m + 1;
      p.stride = stride_for(count, 15.0 * static_cast<double>(m), o.max_terms_per_tau);
      const VarSum v = htot ? htot_var(x, m, tau0, p.stride) : mtot_var(x, m, tau0, p.stride);
      var = v.var;
      p.n_terms = starts(count, p.stride);  // Stable32's '#': the subsequences summed
    }
    if (o.type == LongTau::TTOT) var *= p.tau_s * p.tau_s / 3;
    p.dev = p.dev_raw = std::sqrt(var);
    p.alpha = o.fixed_alpha.value_or(alpha_at(ref, p.tau_s));
    p.alpha = htot ? std::clamp(p.alpha, -4, 2) : std::clamp(p.alpha, -2, 2);
    if (!(htot && m == 1)) p.dev = p.dev_raw / std::sqrt(tot_bias(o.type, p.alpha));
    if (!o.bounds) return;
    p.edf = (htot && m == 1) ? edf_greenhall(std::clamp(p.alpha, -4, 2), 3, 1, n, true, false)
                             : (htot ? edf_htot(p.alpha, n, m) : edf_mtot(p.alpha, n, m));
    if (p.stride > 1) p.edf = std::min(p.edf, static_cast<double>(starts(count, p.stride)));
    set_bounds(p, o.confidence);
  });
  return out;
}

// TheoH (Howe, Taylor & Tasset 2006; SP 1065 sec. 5.2.15):
//   TheoH(m) = AVAR(m)                          for tau = m tau0 < k,
//            = [AVAR/Theo1 ratio] * Theo1(m)     for tau = 0.75 m tau0 >= k, m even,
// k the largest tau <= 20 % of T. The ratio is TheoBR's (SP 1065 eq. 31):
//   (1/(n+1)) sum_{i=0}^{n} AVAR(m = 9 + 3i) / Theo1(m = 12 + 4i),  n = floor(0.1 N / 3 - 3),
// both at tau = (9 + 3i) tau0. For n + 1 > kMaxRatioTerms the mean is taken over that many i
// spread evenly over 0..n (a large record's ratio terms differ little from their neighbours).
inline constexpr std::size_t kMaxRatioTerms = 64;

std::vector<LongTauPoint> theoh_points(const std::vector<double>& x, const LongTauOptions& o,
                                       std::span<const DevPoint> ref) {
  const std::size_t n = x.size();
  const double nn = static_cast<double>(n);
  if (nn / 30.0 - 3 < 0) throw std::invalid_argument("theoh: needs at least 90 phase points (TheoBR's n >= 0)");
  const auto nr = static_cast<std::size_t>(std::floor(0.1 * nn / 3.0 - 3));
  std::vector<std::size_t> is;
  if (nr + 1 <= kMaxRatioTerms) {
    for (std::size_t i = 0; i <= nr; ++i) is.push_back(i);
  } else {
    for (std::size_t j = 0; j < kMaxRatioTerms; ++j)
      is.push_back(static_cast<std::size_t>(std::llround(static_cast<double>(j) * nr / (kMaxRatioTerms - 1))));
  }
  DevOptions av;
  av.type = Deviation::OADEV;
  av.data = DataKind::Phase;
  av.rate_hz = o.rate_hz;
  av.bounds = false;
  av.threads = o.threads;
  for (std::size_t i : is) av.factors.push_back(9 + 3 * i);
  const std::vector<DevPoint> avar = deviation(x, av);
  std::vector<std::size_t> tm;
  for (std::size_t i : is) tm.push_back(12 + 4 * i);
  LongTauOptions t1 = o;
  t1.bounds = false;
  const std::vector<LongTauPoint> th = theo1_points(x, tm, t1, ref);
  long double ratio = 0;
  for (std::size_t j = 0; j < is.size(); ++j) ratio += (avar[j].dev * avar[j].dev) / (th[j].dev * th[j].dev);
  const double br = static_cast<double>(ratio / static_cast<long double>(is.size()));

  // The switch: k = the largest tau <= 0.2 T (T = (N-1) tau0), in samples.
  const auto k = static_cast<std::size_t>(std::floor(0.2 * (nn - 1)));
  std::vector<LongTauPoint> out;
  // AVAR part: OADEV (with its noise identification and EDF) on the grid below k.
  DevOptions a;
  a.type = Deviation::OADEV;
  a.data = DataKind::Phase;
  a.rate_hz = o.rate_hz;
  a.taus = o.taus;
  a.confidence = o.confidence;
  a.bounds = o.bounds;
  a.threads = o.threads;
  a.fixed_alpha = o.fixed_alpha;
  a.poll = o.poll;
  for (const DevPoint& d : deviation(x, a)) {
    if (d.m >= k) break;
    LongTauPoint p;
    p.m = d.m;
    p.tau_s = d.tau_s;
    p.n_terms = d.n_terms;
    p.dev = p.dev_raw = d.dev;
    p.lo = d.lo;
    p.hi = d.hi;
    p.edf = d.edf;
    p.alpha = d.alpha;
    p.estimator = "avar";
    out.push_back(p);
  }
  // Theo1 part: even m with 0.75 m >= k, on the grid up to N-1.
  LongTauOptions g = o;
  g.factors.clear();
  std::vector<std::size_t> ms;
  const std::size_t first = static_cast<std::size_t>(std::ceil(static_cast<double>(k) / 0.75));
  for (std::size_t f : grid(g, n - 1, true, 2))
    if (f >= first) ms.push_back(f);
  for (LongTauPoint p : theo1_points(x, ms, o, ref)) {
    p.dev = p.dev_raw * std::sqrt(br);
    p.estimator = "theobr";
    if (o.bounds && p.bounds_note.empty()) set_bounds(p, o.confidence);  // (a note: none at this EDF)
    out.push_back(p);
  }
  return out;
}

}  // namespace

std::vector<LongTauPoint> long_tau(std::span<const double> data, const LongTauOptions& o) {
  validate(data, o);
  const std::vector<double> x = detrended_phase(data, o.data, o.rate_hz);
  const std::size_t n = x.size();
  const std::size_t need = (o.type == LongTau::Theo1) ? 3 : (o.type == LongTau::HTOT ? 4 : 3);
  if (n < need)
    throw std::invalid_argument(std::string(to_string(o.type)) + ": needs at least " + std::to_string(need) +
                                " phase points, got " + std::to_string(n));
  // Noise types: the caller's OADEV, or an octave OADEV of this record.
  std::vector<DevPoint> own;
  std::span<const DevPoint> ref = o.noise_ref;
  if ((o.bounds || o.type != LongTau::Theo1) && !o.fixed_alpha && ref.empty() && n >= 3) {
    DevOptions d;
    d.type = Deviation::OADEV;
    d.data = DataKind::Phase;
    d.rate_hz = o.rate_hz;
    d.threads = o.threads;
    d.poll = o.poll;
    own = deviation(x, d);
    ref = own;
  }
  switch (o.type) {
    case LongTau::Theo1: return theo1_points(x, grid(o, n - 1, true, 2), o, ref);
    case LongTau::TheoH: return theoh_points(x, o, ref);
    default: return tot_points(x, o, ref);
  }
}

}  // namespace rig::analysis
