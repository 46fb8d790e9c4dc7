// Deviation values, noise identification and bounds from the engine's raw sums.
#include "analysis/allan.hpp"

#include "analysis/drift.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>

#include "analysis/allan_engine.hpp"
#include "analysis/clones.hpp"
#include "analysis/edf.hpp"
#include "analysis/huge_buffer.hpp"
#include "analysis/noise_id.hpp"

namespace rig::analysis {

namespace {

constexpr std::size_t kNoiseIdCap = 1u << 17;  // averaged points used by the lag-1 ACF (see docs)
constexpr std::size_t kAcfMinPoints = 30;      // Stable32: ACF method from 30 averaged points
// The EDF guard acts where B1's type claims more than twice the EDF of the ACF's type below:
// a real change of noise type between neighbouring octaves moves the EDF by less (Greenhall's
// EDF: white and random-walk FM differ by at most 1.8x at equal m and N,
// tests/analysis/test_edf_guard.cpp), a PM reading on an FM
// curve by 3x-30x (issue 12: 25x). Stable32's tables stay unchanged (every one < 2x).
constexpr double kEdfGuardRatio = 2.0;
constexpr std::size_t kAcfReliablePoints = 100;  // the ACF's type from fewer is guarded the same way

int diff_order(Deviation d) { return (d == Deviation::HDEV || d == Deviation::OHDEV) ? 3 : 2; }

// sigma^2 from the engine sum (P in frequency-sum units, see allan_engine.hpp).
double variance(Deviation d, double sum, std::size_t terms, std::size_t m, std::uint64_t n) {
  const double mm = static_cast<double>(m);
  switch (d) {
    case Deviation::ADEV:
    case Deviation::OADEV: return sum / (2 * mm * mm * static_cast<double>(terms));
    case Deviation::MDEV:
    case Deviation::TDEV: return sum / (2 * mm * mm * mm * mm * static_cast<double>(terms));
    case Deviation::HDEV:
    case Deviation::OHDEV: return sum / (6 * mm * mm * static_cast<double>(terms));
    case Deviation::TOTDEV: return sum / (2 * mm * mm * static_cast<double>(n - 2));
  }
  return 0;
}

// Frequency averages over m from the decimated phase, z_k = (P[(k+1)m] - P[km]) / m, into a
// buffer the calling thread reuses: a fresh vector of up to 2^17 values per tau cost a page
// fault and the zeroing of each of its pages, a third of the identification's CPU. The buffer is
// on a transparent huge page where the kernel offers one: its 256 4-KiB pages were still 256
// faults per thread and run, 0.4 ms of the first tau's 0.5 ms (2026-11-24, one thread).
std::span<const double> averages(const detail::Decimated& dec, std::size_t m) {
  if (dec.size() < 2) return {};
  thread_local detail::HugeBuffer buf;
  thread_local std::size_t cap = 0;
  const std::size_t len = dec.size() - 1;
  if (cap < len) buf = detail::huge_buffer(len, &cap);
  double* const out = buf.get();
  const double mm = static_cast<double>(m);
  for (std::size_t k = 0; k < len; ++k) out[k] = (dec[k + 1] - dec[k]) / mm;
  return {out, len};
}

int clamp_alpha(int alpha, int d) { return std::clamp(alpha, d == 3 ? -4 : -2, 2); }

double edf_for(Deviation type, int alpha, std::size_t m, std::uint64_t n) {
  switch (type) {
    case Deviation::ADEV: return edf_greenhall(alpha, 2, m, n, false, false);
    case Deviation::OADEV: return edf_greenhall(alpha, 2, m, n, true, false);
    case Deviation::MDEV:
    case Deviation::TDEV: return edf_greenhall(alpha, 2, m, n, true, true);
    case Deviation::HDEV: return edf_greenhall(alpha, 3, m, n, false, false);
    case Deviation::OHDEV: return edf_greenhall(alpha, 3, m, n, true, false);
    case Deviation::TOTDEV: return edf_totdev(n, m, alpha);
  }
  return 0;
}

void validate(const DevOptions& o) {
  if (!(o.rate_hz > 0) || !std::isfinite(o.rate_hz))
    throw std::invalid_argument("allan: rate must be a positive number of Hz, got " + std::to_string(o.rate_hz));
  if (o.bounds && !(o.confidence > 0 && o.confidence < 1))
    throw std::invalid_argument("allan: confidence must be in (0, 1), got " + std::to_string(o.confidence));
}

std::vector<std::size_t> factors_for(const DevOptions& o, std::uint64_t n) {
  // A record too short for any factor is said as such (it read "averaging factor 1 is out of
  // range for 3 phase points": a review).
  if (!factor_in_range(o.type, n, 1)) {
    std::uint64_t need = n + 1;
    while (need < 64 && !factor_in_range(o.type, need, 1)) ++need;
    throw std::invalid_argument(std::string(to_string(o.type)) + ": needs at least " + std::to_string(need) +
                                " phase points, got " + std::to_string(n));
  }
  if (o.factors.empty()) return tau_factors(o.taus, o.type, n);
  for (std::size_t m : o.factors)
    if (!factor_in_range(o.type, n, m))
      throw std::invalid_argument("allan: averaging factor " + std::to_string(m) + " is out of range for " +
                                  std::to_string(n) + " phase points");
  return o.factors;
}

}  // namespace

bool factor_in_range(Deviation d, std::uint64_t n_phase, std::size_t m) {
  const std::uint64_t top = d == Deviation::TOTDEV ? (n_phase - 1) / 2 : n_phase;
  return m > 0 && m <= top && term_count(d, n_phase, m) > 0;
}

std::vector<std::vector<DevPoint>> deviations_stream(const ChunkSource& src, std::span<const DevOptions> opts,
                                                     const StreamOptions& so) {
  if (opts.empty()) return {};
  for (const auto& o : opts) {
    validate(o);
    if (o.data != opts[0].data || o.rate_hz != opts[0].rate_hz)
      throw std::invalid_argument("allan: deviations in one pass must share data kind and rate");
  }
  const DataKind kind = opts[0].data;
  const std::uint64_t n_src = src.size();
  const std::uint64_t n = kind == DataKind::Frequency ? n_src + 1 : n_src;
  if (n < 3) throw std::invalid_argument("allan: needs at least 3 phase points, got " + std::to_string(n));

  // Requests: every (type, m) once (TDEV is MDEV scaled).
  std::vector<detail::EngineRequest> req;
  std::vector<std::vector<std::size_t>> index(opts.size());
  auto find_or_add = [&](Deviation t, std::size_t m) {
    for (std::size_t i = 0; i < req.size(); ++i)
      if (req[i].type == t && req[i].m == m) return i;
    req.push_back({t, m});
    return req.size() - 1;
  };
  const auto engine_type = [](Deviation t) { return t == Deviation::TDEV ? Deviation::MDEV : t; };
  for (std::size_t k = 0; k < opts.size(); ++k)
    for (std::size_t m : factors_for(opts[k], n)) index[k].push_back(find_or_add(engine_type(opts[k].type), m));
  // A reference tau for the EDF guard (below): where no requested tau of a deviation has a lag-1
  // ACF reading from kAcfReliablePoints averages or more, the longest power-of-two factor that has
  // one is identified too, for the guard alone (never reported). Without it a point's EDF hung on
  // which other taus were asked for (an analysis review: white FM, m:251 alone read flicker PM with
  // EDF 23; m:250,251 gave 4). Where a requested tau has such a reading nothing changes: it is
  // longer than the reference, so the guard reads it as before.
  std::vector<std::optional<std::size_t>> reference(opts.size());
  for (std::size_t k = 0; k < opts.size(); ++k) {
    const DevOptions& o = opts[k];
    if (!o.bounds || !o.edf_guard || o.fixed_alpha || n - 1 < kAcfReliablePoints) continue;
    const auto reliable = [&](std::size_t i) { return (n - 1) / req[i].m >= kAcfReliablePoints; };
    if (std::any_of(index[k].begin(), index[k].end(), reliable)) continue;
    const std::size_t m_ref = std::bit_floor(static_cast<std::size_t>((n - 1) / kAcfReliablePoints));
    if (factor_in_range(o.type, n, m_ref)) reference[k] = find_or_add(engine_type(o.type), m_ref);
  }
  StreamOptions so_polled = so;
  if (!so_polled.poll) so_polled.poll = opts[0].poll;
  const auto poll = [&so_polled] {
    if (so_polled.poll) so_polled.poll();
  };
  poll();
  detail::Engine engine(src, kind, opts[0].rate_hz, so_polled, opts[0].threads, kNoiseIdCap);
  const detail::EngineResult er = engine.run(req);
  // The phase's frequency values are one fewer than its points (phase data: their differences).
  if (so.drift) *so.drift = drift_from_phase_sums(n - 1, er.phase_last, er.phase_sum, 1 / opts[0].rate_hz);
  if (so.phase_abs_max) *so.phase_abs_max = er.phase_abs_max;

  // Mod AVAR at m for R(n), only where B1 cannot tell white from flicker PM.
  std::map<std::size_t, double> mvar_cache;
  auto mod_avar = [&](std::size_t m) {
    if (auto it = mvar_cache.find(m); it != mvar_cache.end()) return it->second;
    double v = -1;
    for (std::size_t i = 0; i < req.size(); ++i)
      if (req[i].type == Deviation::MDEV && req[i].m == m)
        v = variance(Deviation::MDEV, er.sums[i].sum, er.sums[i].terms, m, n);
    if (v < 0 && term_count(Deviation::MDEV, n, m) > 0) {
      const detail::Sums s = engine.extra(Deviation::MDEV, m);
      v = variance(Deviation::MDEV, s.sum, s.terms, m, n);
    }
    return mvar_cache[m] = v;
  };

  // First, per point and in parallel: the deviation and, with >= 30 averages, the lag-1 ACF
  // noise identification (the costly part: up to kNoiseIdCap points per tau).
  struct Pending {
    std::size_t k, q;
    DevPoint p;
    std::vector<double> z;
    std::optional<NoiseId> id;
    bool bounded = false;  // alpha, EDF and bounds already set (they need no other tau's alpha)
    std::size_t averages = 0;  // the averaged values its noise identification read
    std::optional<std::size_t> reference;  // the guard's reference tau (its request), not reported
  };
  std::vector<Pending> pend;
  for (std::size_t k = 0; k < opts.size(); ++k) {
    for (std::size_t q = 0; q < index[k].size(); ++q) pend.push_back({k, q, {}, {}, {}, false, 0, std::nullopt});
    if (reference[k]) pend.push_back({k, 0, {}, {}, {}, false, 0, reference[k]});
  }
  const auto sums_of = [&](const Pending& e) -> const detail::Sums& {
    return er.sums[e.reference ? *e.reference : index[e.k][e.q]];
  };
  // A tau's alpha, EDF and chi-square bounds, where its alpha is its own: fixed, or identified
  // by the lag-1 ACF (no EDF guard then). Computed in the parallel loop below; the B1 taus, whose
  // rules read the previous tau's alpha, follow in order (the same calls either way).
  const auto bound = [](DevPoint& p, int alpha, const DevOptions& o, std::uint64_t n_phase) {
    const int d = diff_order(o.type);
    p.alpha = clamp_alpha(alpha, d);
    p.edf = edf_for(o.type, p.alpha, p.m, n_phase);
    p.edf_alpha = p.alpha;
  };
  const double tau0 = 1.0 / opts[0].rate_hz;
  const unsigned threads = opts[0].threads ? opts[0].threads : std::max(1u, std::thread::hardware_concurrency());
  detail::parallel_for(pend.size(), threads, [&](std::size_t i) {
    poll();
    Pending& e = pend[i];
    const DevOptions& o = opts[e.k];
    const detail::Sums& s = sums_of(e);
    DevPoint& p = e.p;
    p.m = s.m;
    p.tau_s = static_cast<double>(s.m) * tau0;
    p.n_terms = term_count(o.type, n, s.m);
    p.dev = std::sqrt(variance(o.type, s.sum, s.terms, s.m, n));
    if (o.type == Deviation::TDEV) p.dev *= p.tau_s / std::sqrt(3.0);
    if (!o.bounds) return;
    const auto finish = [&](int alpha) {
      bound(p, alpha, o, n);
      std::tie(p.lo, p.hi) = chi2_bounds(p.dev, p.edf, o.confidence);
      e.bounded = true;
    };
    if (o.fixed_alpha) return finish(*o.fixed_alpha);
    const detail::Decimated& dec = er.decimated.at(s.m);
    const std::span<const double> z = averages(dec, s.m);
    e.averages = z.size();
    if (z.size() < kAcfMinPoints) {  // kept for B1/R(n) below
      e.z.assign(z.begin(), z.end());
      return;
    }
    if (kind == DataKind::Frequency) {
      e.id = acf_noise_id(z, false, diff_order(o.type));
    } else {
      // Phase data: Stable32 identifies on the decimated phase itself (noise_id.hpp). The
      // engine's P is the phase less the line through its end points, in units of tau0; the
      // line is put back (an ACF sees it before differencing), the scale does not matter.
      std::vector<double> x(dec.size());
      const double ramp = er.spec.slope * er.spec.rate_hz * static_cast<double>(s.m);
      for (std::size_t j = 0; j < x.size(); ++j) x[j] = dec[j] + ramp * static_cast<double>(j);
      e.id = acf_noise_id(x, true, diff_order(o.type));
    }
    finish(e.id->alpha);
  });

  // The alpha of the longest tau below m (same deviation) that the lag-1 ACF identified from at
  // least `min_averages` values.
  auto acf_alpha_below = [](const std::vector<Pending>& all, const Pending& me, std::size_t m,
                            std::size_t min_averages = 0) -> std::optional<int> {
    std::optional<int> a;
    std::size_t best = 0;
    for (const Pending& q : all)
      if (q.k == me.k && q.id && q.averages >= min_averages && q.p.m < m && q.p.m >= best) {
        best = q.p.m;
        a = q.id->alpha;
      }
    return a;
  };

  // Then in order: B1/R(n) where there are fewer than 30 averages (its rules repeat the alpha
  // of the previous tau past half the largest factor), and the bounds.
  std::vector<std::vector<DevPoint>> out(opts.size());
  for (Pending& e : pend) {
    if (e.reference) continue;  // the guard's reference: read below, never reported
    const DevOptions& o = opts[e.k];
    const detail::Sums& s = sums_of(e);
    DevPoint p = e.p;
    // The same guard where the lag-1 ACF read few values (30 to 99: r1's standard error 0.1-0.18,
    // enough to read flicker PM on a white-FM curve, EDF 9x too large: a review), against the
    // type it read from 100 or more.
    if (o.bounds && e.bounded && e.id && o.edf_guard && e.averages < kAcfReliablePoints) {
      const int d = diff_order(o.type);
      if (const auto ref = acf_alpha_below(pend, e, s.m, kAcfReliablePoints)) {
        const int ra = clamp_alpha(*ref, d);
        const double cap = edf_for(o.type, ra, s.m, n);
        if (p.edf > kEdfGuardRatio * cap) {
          p.edf = cap;
          p.edf_alpha = ra;
          std::tie(p.lo, p.hi) = chi2_bounds(p.dev, p.edf, o.confidence);
        }
      }
    }
    if (o.bounds && !e.bounded) {  // B1/R(n): fewer than 30 averages
      const int d = diff_order(o.type);
      std::optional<int> previous;
      std::size_t previous_m = 0;
      for (const DevPoint& prior : out[e.k]) {
        if (prior.m < s.m && prior.m >= previous_m) {
          previous_m = prior.m;
          previous = prior.alpha;
        }
      }
      const bool modified = o.type == Deviation::MDEV || o.type == Deviation::TDEV;
      const NoiseId id = b1_rn_noise_id(e.z, {s.m, p.n_terms, max_factor(o.type, n), d == 3, previous},
                                        modified ? std::function<double()>([&] { return mod_avar(s.m); }) : nullptr);
      bound(p, id.alpha, o, n);
      // The EDF guard (docs/analysis.md, "EDF guard at long tau"): with fewer than 30 averages
      // the B1 rule reads a few values, and a type that contradicts the reliably identified
      // (lag-1 ACF) taus below may not claim more degrees of freedom than that type gives.
      if (o.edf_guard) {
        // Against a type read from 100 or more values where there is one (a reading from fewer may
        // be the misreading the guard below corrects: a code review), else the ACF's last.
        std::optional<int> reliable = acf_alpha_below(pend, e, s.m, kAcfReliablePoints);
        if (const auto ref = reliable ? reliable : acf_alpha_below(pend, e, s.m)) {
          const int ra = clamp_alpha(*ref, d);
          const double cap = edf_for(o.type, ra, s.m, n);
          if (p.edf > kEdfGuardRatio * cap) {
            p.edf = cap;
            p.edf_alpha = ra;
          }
        }
      }
      const auto [lo, hi] = chi2_bounds(p.dev, p.edf, o.confidence);
      p.lo = lo;
      p.hi = hi;
    }
    out[e.k].push_back(p);
  }
  return out;
}

std::vector<DevPoint> deviation_stream(const ChunkSource& src, const DevOptions& opt, const StreamOptions& so) {
  return deviations_stream(src, std::span<const DevOptions>(&opt, 1), so)[0];
}

std::optional<std::size_t> first_non_finite(std::span<const double> v) {
  // x * 0 is NaN exactly for NaN and infinities; explicit lanes keep the pass vectorised
  // without reassociating a floating-point sum.
  using v4 = double __attribute__((vector_size(32)));
  v4 acc{};
  std::size_t i = 0;
  for (; i + 4 <= v.size(); i += 4) {
    v4 x;
    std::memcpy(&x, v.data() + i, sizeof x);
    acc += x * 0.0;
  }
  double tail = 0;
  for (; i < v.size(); ++i) tail += v[i] * 0.0;
  if (acc[0] + acc[1] + acc[2] + acc[3] + tail == 0.0) return std::nullopt;  // NaN != 0
  for (i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) return i;
  return std::nullopt;
}

namespace {

// x * 2^691 is exact below 2^333 in magnitude and overflows to inf from there; times 0 that is
// NaN, as it is for NaN and inf: one multiply and one add per value, summed in 32 explicit
// lanes (vectorised without reassociating a floating-point sum: the lanes are 0 or NaN), four
// independent accumulators so no chain of dependent additions bounds it, compiled for
// AVX-512, AVX2 and baseline (this check runs on every value of every record, in the pass).
RIG_CLONES bool any_unusable(const double* p, std::size_t n) {
  using v8 = double __attribute__((vector_size(64)));
  constexpr double kScale = 0x1p691;  // 2^1024 / kMaxMagnitude
  v8 a0{}, a1{}, a2{}, a3{};
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    v8 x0, x1, x2, x3;
    std::memcpy(&x0, p + i, sizeof x0);
    std::memcpy(&x1, p + i + 8, sizeof x1);
    std::memcpy(&x2, p + i + 16, sizeof x2);
    std::memcpy(&x3, p + i + 24, sizeof x3);
    a0 += (x0 * kScale) * 0.0, a1 += (x1 * kScale) * 0.0, a2 += (x2 * kScale) * 0.0, a3 += (x3 * kScale) * 0.0;
  }
  const v8 a = (a0 + a1) + (a2 + a3);
  double acc = 0;
  for (int l = 0; l < 8; ++l) acc += a[l];
  for (; i < n; ++i) acc += (p[i] * kScale) * 0.0;
  return acc != 0.0;  // NaN != 0
}

}  // namespace

std::optional<std::size_t> first_unusable(std::span<const double> v) {
  // One vectorised pass (any_unusable), then a search only when there is one.
  if (!any_unusable(v.data(), v.size())) return std::nullopt;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!(std::fabs(v[i]) < kMaxMagnitude)) return i;
  return std::nullopt;
}

std::vector<DevPoint> deviation(std::span<const double> data, const DevOptions& opt) {
  if (const auto bad = first_unusable(data)) {
    const double x = data[*bad];
    char shown[32];
    std::snprintf(shown, sizeof shown, "%.17g", x);
    throw std::invalid_argument("allan: value " + std::to_string(*bad) + " (" + shown + ") is " +
                                (std::isfinite(x) ? "beyond +-2^333 (1.7e100)" : "not finite"));
  }
  SpanSource src(data);
  StreamOptions so;
  so.memory_budget_bytes = std::numeric_limits<std::size_t>::max() / 4;  // in memory: one ring holds it all
  return deviation_stream(src, opt, so);
}

}  // namespace rig::analysis
