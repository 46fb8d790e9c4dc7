// GOST R 8.736-2011 "direct multiple measurements": processing of the 100 s means (bias, base
// error: mean, standard deviation, Student's interval, outliers). The in-run random component
// B = (max - min)/2 is the Russian enterprises' practice the paper gives as conforming to that
// standard; the standard itself has no half-range statistic (docs/method.md).
#pragma once
#include <cstddef>
#include <span>
#include <vector>

namespace rig::analysis {

struct GostSummary {
  std::size_t n = 0;
  double mean = 0, sd = 0, sd_mean = 0;  // sd: sample standard deviation (n - 1); sd_mean = sd / sqrt(n)
  double t_coef = 0;                     // Student's t for (1 + confidence)/2, n - 1 degrees of freedom
  double ci_half = 0, ci_lo = 0, ci_hi = 0, confidence = 0.95;
  std::vector<std::size_t> outliers;     // indices flagged by the Grubbs test (two-sided, repeated)
  double grubbs_stat = 0, grubbs_crit = 0;  // of the first (most extreme) candidate
};

// Throws std::invalid_argument for n < 2 or a confidence outside (0, 1).
// Outliers are reported, not removed: the statistics are of all n values, as the
// procedure records them; the caller decides what to do with a flagged run.
GostSummary gost_summary(std::span<const double> x, double confidence = 0.95);

// Grubbs critical value G_crit(n, significance) for the two-sided test (GOST R 8.736 Annex / ISO 5725-2).
double grubbs_critical(std::size_t n, double significance = 0.05);

// Means of consecutive full blocks of block_len values; a trailing partial block is dropped.
std::vector<double> block_means(std::span<const double> x, std::size_t block_len);

struct InRunB {
  double value = 0;       // (max - min) / 2 of the block means (docs/method.md, procedure B)
  std::size_t blocks = 0;
  double max_mean = 0, min_mean = 0;
};
// Throws std::invalid_argument when fewer than 2 full blocks fit.
InRunB in_run_b(std::span<const double> x, std::size_t block_len);

}  // namespace rig::analysis
