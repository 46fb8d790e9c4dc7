// GOST R 8.736-2011 processing: mean, SD, SD of the mean, Student interval, Grubbs; the
// (max - min)/2 in-run rule. Expected values from the standard's formulas worked by hand
// and from published Student/Grubbs tables.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/gost.hpp"

namespace rig::analysis {
namespace {

TEST(Gost, SummaryOfFiveValues) {
  const std::vector<double> x = {1, 2, 3, 4, 5};
  const GostSummary s = gost_summary(x);
  EXPECT_EQ(s.n, 5u);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_NEAR(s.sd, std::sqrt(2.5), 1e-12);
  EXPECT_NEAR(s.sd_mean, std::sqrt(2.5 / 5), 1e-12);
  EXPECT_NEAR(s.t_coef, 2.7764, 1e-4);  // t(0.975, 4), Student table
  EXPECT_NEAR(s.ci_half, 2.7764 * std::sqrt(0.5), 1e-4);
  EXPECT_NEAR(s.ci_lo, 3 - s.ci_half, 1e-12);
  EXPECT_TRUE(s.outliers.empty());
}

TEST(Gost, SixRunsOfTheBiasAtTheirRealScale) {
  // Offsets like the paper's bias (-5e-4 g) with 1e-6 g scatter: no cancellation trouble.
  const std::vector<double> x = {-5.0137e-4, -5.0142e-4, -5.0131e-4, -5.0139e-4, -5.0135e-4, -5.0138e-4};
  const GostSummary s = gost_summary(x, 0.95);
  EXPECT_NEAR(s.mean, -5.0137e-4, 1e-9);
  EXPECT_NEAR(s.t_coef, 2.5706, 1e-4);  // t(0.975, 5)
  EXPECT_GT(s.sd, 3e-8);
  EXPECT_LT(s.sd, 5e-8);
}

TEST(Gost, GrubbsCriticalValuesMatchTheTable) {
  // Two-sided 5 % (ISO 5725-2 Table 5 / GOST R 8.736 Annex): n=3 1.155, n=6 1.887, n=10 2.290, n=18 2.652... 
  EXPECT_NEAR(grubbs_critical(3), 1.155, 2e-3);
  EXPECT_NEAR(grubbs_critical(6), 1.887, 2e-3);
  EXPECT_NEAR(grubbs_critical(10), 2.290, 2e-3);
  EXPECT_NEAR(grubbs_critical(20), 2.709, 2e-3);
  EXPECT_THROW(grubbs_critical(2), std::invalid_argument);
}

TEST(Gost, GrubbsFlagsTheWildRunOnly) {
  const std::vector<double> x = {10.0, 10.1, 9.9, 10.2, 9.8, 10.05, 9.95, 15.0};
  const GostSummary s = gost_summary(x);
  ASSERT_EQ(s.outliers.size(), 1u);
  EXPECT_EQ(s.outliers[0], 7u);
  EXPECT_GT(s.grubbs_stat, s.grubbs_crit);
  const GostSummary clean = gost_summary(std::vector<double>(x.begin(), x.end() - 1));
  EXPECT_TRUE(clean.outliers.empty());
  EXPECT_LT(clean.grubbs_stat, clean.grubbs_crit);
}

TEST(Gost, RejectsTooFewOrBadValues) {
  EXPECT_THROW(gost_summary(std::vector<double>{1.0}), std::invalid_argument);
  EXPECT_THROW(gost_summary(std::vector<double>{1.0, 2.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(gost_summary(std::vector<double>{1.0, std::nan("")}), std::invalid_argument);
}

TEST(InRun, BlockMeansDropThePartialBlock) {
  std::vector<double> x;
  for (int i = 0; i < 10; ++i) x.push_back(i);
  const auto m = block_means(x, 4);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_DOUBLE_EQ(m[0], 1.5);
  EXPECT_DOUBLE_EQ(m[1], 5.5);
  EXPECT_THROW(block_means(x, 0), std::invalid_argument);
}

TEST(InRun, HalfRangeOfEighteenHundredSecondMeans) {
  // 30 min at 1 kHz in 100 s blocks: 18 means; one block shifted by +8e-6 g, one by -0 g.
  const std::size_t block = 100000;
  std::vector<double> x(18 * block + 123, -5e-4);
  for (std::size_t i = 5 * block; i < 6 * block; ++i) x[i] += 8e-6;
  const InRunB b = in_run_b(x, block);
  EXPECT_EQ(b.blocks, 18u);
  EXPECT_NEAR(b.value, 4e-6, 1e-12);  // the paper's 100 s figure
  EXPECT_NEAR(b.max_mean, -5e-4 + 8e-6, 1e-12);
  const InRunB b2 = in_run_b(x, 2 * block);  // 200 s: 9 means, the shifted block halves
  EXPECT_EQ(b2.blocks, 9u);
  EXPECT_NEAR(b2.value, 2e-6, 1e-12);
  EXPECT_THROW(in_run_b(x, 10 * block), std::invalid_argument);
}

}  // namespace
}  // namespace rig::analysis
