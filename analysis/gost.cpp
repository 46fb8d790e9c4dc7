#include "analysis/gost.hpp"

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace rig::analysis {

namespace {

struct MeanSd {
  double mean, sd;
};

// Two-pass mean and sample standard deviation (numerically safe for offsets like -5e-4 g).
MeanSd mean_sd(std::span<const double> x) {
  const double n = static_cast<double>(x.size());
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / n;
  double ss = 0;
  for (double v : x) ss += (v - mean) * (v - mean);
  return {mean, x.size() > 1 ? std::sqrt(ss / (n - 1)) : 0.0};
}

}  // namespace

double grubbs_critical(std::size_t n, double significance) {
  if (n < 3) throw std::invalid_argument("grubbs_critical: needs n >= 3, got " + std::to_string(n));
  // G_crit = (n-1)/sqrt(n) * sqrt(t^2 / (n - 2 + t^2)), t = t_{alpha/(2n), n-2} (Grubbs 1969).
  const double nn = static_cast<double>(n);
  boost::math::students_t dist(nn - 2);
  const double t = boost::math::quantile(boost::math::complement(dist, significance / (2 * nn)));
  return (nn - 1) / std::sqrt(nn) * std::sqrt(t * t / (nn - 2 + t * t));
}

GostSummary gost_summary(std::span<const double> x, double confidence) {
  if (x.size() < 2) throw std::invalid_argument("gost_summary: needs at least 2 values, got " + std::to_string(x.size()));
  if (!(confidence > 0 && confidence < 1))
    throw std::invalid_argument("gost_summary: confidence must be in (0, 1), got " + std::to_string(confidence));
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i])) throw std::invalid_argument("gost_summary: value " + std::to_string(i) + " is not finite");

  GostSummary s;
  s.n = x.size();
  s.confidence = confidence;
  const MeanSd ms = mean_sd(x);
  s.mean = ms.mean;
  s.sd = ms.sd;
  s.sd_mean = ms.sd / std::sqrt(static_cast<double>(s.n));
  boost::math::students_t dist(static_cast<double>(s.n - 1));
  s.t_coef = boost::math::quantile(boost::math::complement(dist, (1 - confidence) / 2));
  s.ci_half = s.t_coef * s.sd_mean;
  s.ci_lo = s.mean - s.ci_half;
  s.ci_hi = s.mean + s.ci_half;

  // Repeated two-sided Grubbs test at the complementary significance (GOST R 8.736 clause 6.3).
  if (s.n >= 3) {
    std::vector<std::size_t> idx(s.n);
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    bool first = true;
    while (idx.size() >= 3) {
      std::vector<double> vals;
      vals.reserve(idx.size());
      for (std::size_t i : idx) vals.push_back(x[i]);
      const MeanSd cur = mean_sd(vals);
      if (cur.sd == 0) break;
      std::size_t worst = 0;
      for (std::size_t k = 1; k < vals.size(); ++k)
        if (std::abs(vals[k] - cur.mean) > std::abs(vals[worst] - cur.mean)) worst = k;
      const double g = std::abs(vals[worst] - cur.mean) / cur.sd;
      const double crit = grubbs_critical(vals.size(), 1 - confidence);
      if (first) {
        s.grubbs_stat = g;
        s.grubbs_crit = crit;
        first = false;
      }
      if (g <= crit) break;
      s.outliers.push_back(idx[worst]);
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(worst));
    }
    std::sort(s.outliers.begin(), s.outliers.end());
  }
  return s;
}

std::vector<double> block_means(std::span<const double> x, std::size_t block_len) {
  if (block_len == 0) throw std::invalid_argument("block_means: block length must be > 0");
  std::vector<double> out;
  out.reserve(x.size() / block_len);
  for (std::size_t b = 0; b + block_len <= x.size(); b += block_len) {
    double s = 0;
    for (std::size_t i = b; i < b + block_len; ++i) s += x[i];
    out.push_back(s / static_cast<double>(block_len));
  }
  return out;
}

InRunB in_run_b(std::span<const double> x, std::size_t block_len) {
  const std::vector<double> means = block_means(x, block_len);
  if (means.size() < 2)
    throw std::invalid_argument("in_run_b: " + std::to_string(x.size()) + " samples hold " +
                                std::to_string(means.size()) + " full block(s) of " + std::to_string(block_len) +
                                "; at least 2 are needed");
  const auto [lo, hi] = std::minmax_element(means.begin(), means.end());
  return {(*hi - *lo) / 2, means.size(), *hi, *lo};
}

}  // namespace rig::analysis
