// Deviation values, noise identification and bounds from the engine's raw sums.
#include "procedures/analysis/allan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "procedures/analysis/allan_engine.hpp"
#include "procedures/analysis/edf.hpp"
#include "procedures/analysis/noise_id.hpp"

namespace rig::analysis {

namespace {

constexpr std::size_t kNoiseIdCap = 1u << 17;  // averaged points used by the lag-1 ACF (see docs)
constexpr std::size_t kAcfMinPoints = 30;      // Stable32: ACF method from 30 averaged points

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

// Frequency averages over m from the decimated phase, z_k = (P[(k+1)m] - P[km]) / m.
std::vector<double> averages(const std::vector<double>& dec, std::size_t m) {
  std::vector<double> z;
  if (dec.size() < 2) return z;
  z.reserve(dec.size() - 1);
  for (std::size_t k = 0; k + 1 < dec.size(); ++k) z.push_back((dec[k + 1] - dec[k]) / static_cast<double>(m));
  return z;
}

double sample_variance(const std::vector<double>& z) {
  double mu = 0;
  for (double v : z) mu += v;
  mu /= static_cast<double>(z.size());
  double s = 0;
  for (double v : z) s += (v - mu) * (v - mu);
  return s / static_cast<double>(z.size() - 1);
}

std::vector<double> detrend_linear(const std::vector<double>& z) {
  const double n = static_cast<double>(z.size()), tm = (n - 1) / 2;
  double zm = 0;
  for (double v : z) zm += v;
  zm /= n;
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    const double t = static_cast<double>(i) - tm;
    sxy += t * (z[i] - zm);
    sxx += t * t;
  }
  const double b = sxx > 0 ? sxy / sxx : 0;
  std::vector<double> r(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) r[i] = z[i] - zm - b * (static_cast<double>(i) - tm);
  return r;
}

double nonoverlapped_avar(const std::vector<double>& z) {
  double s = 0;
  for (std::size_t k = 0; k + 1 < z.size(); ++k) s += (z[k + 1] - z[k]) * (z[k + 1] - z[k]);
  return s / (2 * static_cast<double>(z.size() - 1));
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
  if (o.factors.empty()) return tau_factors(o.taus, o.type, n);
  const std::uint64_t top = o.type == Deviation::TOTDEV ? (n - 1) / 2 : n;
  for (std::size_t m : o.factors)
    if (m == 0 || m > top || term_count(o.type, n, m) == 0)
      throw std::invalid_argument("allan: averaging factor " + std::to_string(m) + " is out of range for " +
                                  std::to_string(n) + " phase points");
  return o.factors;
}

}  // namespace

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
  for (std::size_t k = 0; k < opts.size(); ++k)
    for (std::size_t m : factors_for(opts[k], n))
      index[k].push_back(find_or_add(opts[k].type == Deviation::TDEV ? Deviation::MDEV : opts[k].type, m));
  detail::Engine engine(src, kind, opts[0].rate_hz, so, opts[0].threads, kNoiseIdCap);
  const detail::EngineResult er = engine.run(req);

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

  std::vector<std::vector<DevPoint>> out(opts.size());
  const double tau0 = 1.0 / opts[0].rate_hz;
  for (std::size_t k = 0; k < opts.size(); ++k) {
    const DevOptions& o = opts[k];
    for (std::size_t q = 0; q < index[k].size(); ++q) {
      const detail::Sums& s = er.sums[index[k][q]];
      DevPoint p;
      p.m = s.m;
      p.tau_s = static_cast<double>(s.m) * tau0;
      p.n_terms = term_count(o.type, n, s.m);
      double var = variance(o.type, s.sum, s.terms, s.m, n);
      p.dev = std::sqrt(var);
      if (o.type == Deviation::TDEV) p.dev *= p.tau_s / std::sqrt(3.0);
      if (o.bounds) {
        const int d = diff_order(o.type);
        const std::vector<double> z = averages(s.decimated, s.m);
        NoiseId id;
        if (o.fixed_alpha) {
          id.alpha = *o.fixed_alpha;
        } else if (z.size() >= kAcfMinPoints) {
          // Stable32 identifies on the m-averaged frequency for phase data too (matches its tables
          // where the decimated-phase variant of allantools does not: Cs5071A m >= 5000).
          id = acf_noise_id(z, false, d);
        } else if (z.size() >= 3) {
          // B1 on the linearly detrended averages (a frequency drift would otherwise read as
          // random-walk FM), against their non-overlapped Allan variance.
          const std::vector<double> zr = detrend_linear(z);
          const double avar = nonoverlapped_avar(zr);
          const double b1 = avar > 0 ? sample_variance(zr) / avar : 1;
          id = b1_rn_noise_id(b1, static_cast<double>(z.size()), -1, s.m);
          const double av = nonoverlapped_avar(z);
          double rn = -1;
          if (id.alpha >= 1 && av > 0) {  // phase modulation: R(n) = Mod AVAR / AVAR decides
            const double mv = mod_avar(s.m);
            if (mv >= 0) rn = mv / av;
          }
          id = b1_rn_noise_id(b1, static_cast<double>(z.size()), rn, s.m);
        }
        p.alpha = clamp_alpha(id.alpha, d);
        p.edf = edf_for(o.type, p.alpha, s.m, n);
        const auto [lo, hi] = chi2_bounds(p.dev, p.edf, o.confidence);
        p.lo = lo;
        p.hi = hi;
      }
      out[k].push_back(p);
    }
  }
  return out;
}

std::vector<DevPoint> deviation_stream(const ChunkSource& src, const DevOptions& opt, const StreamOptions& so) {
  return deviations_stream(src, std::span<const DevOptions>(&opt, 1), so)[0];
}

std::vector<DevPoint> deviation(std::span<const double> data, const DevOptions& opt) {
  for (std::size_t i = 0; i < data.size(); ++i)
    if (!std::isfinite(data[i])) throw std::invalid_argument("allan: value " + std::to_string(i) + " is not finite");
  SpanSource src(data);
  StreamOptions so;
  so.memory_budget_bytes = std::numeric_limits<std::size_t>::max() / 4;  // in memory: one ring holds it all
  return deviation_stream(src, opt, so);
}

}  // namespace rig::analysis
