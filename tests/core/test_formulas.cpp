// Formulas (3), (4), the sign rule, and the accuracy-class table, against hand-computed cases.
#include <gtest/gtest.h>

#include "procedures/acceptance/procedure.hpp"
#include "analysis/gost.hpp"

using rig::acceptance::accuracy_class;
using rig::acceptance::AccuracyClass;
using rig::acceptance::bias_and_base_error;

TEST(Formulas, BiasAndBaseErrorHandComputed) {
  // x10 = bias + dA + e_i, x20 = bias - dA + f_i with bias = -5e-4, dA = 4e-4.
  const std::vector<double> x10{-1.0e-4, -1.2e-4, -0.8e-4};
  const std::vector<double> x20{-9.0e-4, -8.8e-4, -9.2e-4};
  const auto r = bias_and_base_error(x10, x20);
  // (3): mean of (x10+x20)/2 = ((-5e-4) + (-5e-4) + (-5e-4)) / 3
  EXPECT_NEAR(r.bias, -5.0e-4, 1e-15);
  // (4): mean of (x10-x20)/2 = (4e-4 + 3.8e-4 + 4.2e-4)/3 = 4e-4
  EXPECT_NEAR(r.base_error, 4.0e-4, 1e-15);
  EXPECT_EQ(r.sign_u10, +1);
  ASSERT_TRUE(r.bias_ci_half && r.base_ci_half);
  EXPECT_NEAR(*r.bias_ci_half, 0.0, 1e-15);  // every pair gives exactly -5e-4
  EXPECT_GT(*r.base_ci_half, 0.0);
}

// GOST R 8.736's Grubbs test on the pairs' summands: an outlying pair is named with its runs in the
// value's reason and kept in the value (reported, not removed); none is tested below 3 pairs.
TEST(Formulas, AnOutlyingPairIsReportedNotRemoved) {
  const std::vector<double> x10{-1.0e-4, -1.01e-4, -0.99e-4, -1.0e-4, -2.0e-4, -1.0e-4};
  const std::vector<double> x20{-9.0e-4, -9.0e-4, -9.01e-4, -8.99e-4, -9.0e-4, -9.0e-4};
  const auto r = bias_and_base_error(x10, x20);
  ASSERT_TRUE(r.bias_gost && r.base_gost);
  EXPECT_EQ(r.bias_gost->outliers, std::vector<std::size_t>{4});
  EXPECT_EQ(r.base_gost->outliers, std::vector<std::size_t>{4});
  double sum = 0;
  for (std::size_t i = 0; i < x10.size(); ++i) sum += (x10[i] + x20[i]) / 2;
  EXPECT_DOUBLE_EQ(r.bias, sum / 6);  // the outlier stays in the value
  const std::vector<std::pair<std::size_t, std::size_t>> pairs{{1, 2}, {3, 4}, {5, 6}, {7, 8}, {9, 10}, {11, 12}};
  const std::string note = rig::acceptance::grubbs_note(*r.bias_gost, pairs, nullptr, "bias");
  EXPECT_NE(note.find("Grubbs (5 %): outlier pair 5 (runs 9 U10, 10 U20) among 6 pairs (first G "), std::string::npos)
      << note;
  EXPECT_NE(note.find("kept in the value (GOST R 8.736: reported, not removed)"), std::string::npos) << note;
  const auto calm = bias_and_base_error({-1.0e-4, -1.01e-4, -0.99e-4}, {-9.0e-4, -9.02e-4, -8.98e-4});
  EXPECT_NE(rig::acceptance::grubbs_note(*calm.bias_gost, pairs, nullptr, "bias").find("no outlier among 3 pairs (G "),
            std::string::npos);
  const auto two = bias_and_base_error({-1.0e-4, -1.1e-4}, {-9.0e-4, -9.1e-4});
  EXPECT_EQ(rig::acceptance::grubbs_note(*two.bias_gost, pairs, nullptr, "bias"), "; 2 pairs: no Grubbs test (it needs 3)");
}

// One pair has no scatter to take a GOST interval from: none is given (the passport then
// carries the value without lo/hi and says why), where a zero half-width was reported before.
TEST(Formulas, OnePairHasNoInterval) {
  const auto r = bias_and_base_error({-1.0e-4}, {-9.0e-4});
  EXPECT_NEAR(r.bias, -5.0e-4, 1e-15);
  EXPECT_NEAR(r.base_error, 4.0e-4, 1e-15);
  EXPECT_FALSE(r.bias_ci_half);
  EXPECT_FALSE(r.base_ci_half);
}

TEST(Formulas, SignRuleWhenU20ReadsHigher) {
  // mean(x10) < mean(x20): g_dA enters (1) with minus; it is quoted positive.
  const std::vector<double> x10{-9.0e-4, -9.0e-4};
  const std::vector<double> x20{-1.0e-4, -1.0e-4};
  const auto r = bias_and_base_error(x10, x20);
  EXPECT_NEAR(r.bias, -5.0e-4, 1e-15);
  EXPECT_NEAR(r.base_error, 4.0e-4, 1e-15);
  EXPECT_EQ(r.sign_u10, -1);
}

TEST(Formulas, PaperFiguresRoundTrip) {
  // Six pairs built from the paper's g_sist and g_dA with alternating +-1e-6 noise.
  const double bias = -5.0137e-4, dA = 3.8549e-4;
  std::vector<double> x10, x20;
  for (int i = 0; i < 6; ++i) {
    const double e = (i % 2 ? 1e-6 : -1e-6);
    x10.push_back(bias + dA + e);
    x20.push_back(bias - dA + e);
  }
  const auto r = bias_and_base_error(x10, x20);
  EXPECT_NEAR(r.bias, bias, 1e-16);
  EXPECT_NEAR(r.base_error, dA, 1e-16);
}

TEST(Formulas, RejectsUnpairedRuns) {
  EXPECT_THROW(bias_and_base_error({1.0, 2.0}, {1.0}), std::invalid_argument);
  EXPECT_THROW(bias_and_base_error({}, {}), std::invalid_argument);
}

TEST(Formulas, InRunBRussianMethod) {
  // 18 blocks of 100 samples; block means 0..17 * 1e-6 => B = (17e-6 - 0)/2.
  std::vector<double> x;
  for (int b = 0; b < 18; ++b)
    for (int i = 0; i < 100; ++i) x.push_back(b * 1e-6 + (i % 2 ? 3e-7 : -3e-7));
  const auto b100 = rig::analysis::in_run_b(x, 100);
  EXPECT_EQ(b100.blocks, 18u);
  EXPECT_NEAR(b100.value, 8.5e-6, 1e-15);
  // 200-sample blocks: means 0.5, 2.5, ..., 16.5 (e-6) => B = 8e-6.
  const auto b200 = rig::analysis::in_run_b(x, 200);
  EXPECT_EQ(b200.blocks, 9u);
  EXPECT_NEAR(b200.value, 8.0e-6, 1e-15);
}

TEST(Formulas, AccuracyClassTable) {
  const std::vector<AccuracyClass> c{{"precision", 5e-6}, {"medium", 2e-5}, {"low", 1e-4}};
  EXPECT_EQ(accuracy_class(c, 4e-6), 1u);
  EXPECT_EQ(accuracy_class(c, 5e-6), 1u);
  EXPECT_EQ(accuracy_class(c, 1.9e-5), 2u);
  EXPECT_EQ(accuracy_class(c, 9e-5), 3u);
  EXPECT_FALSE(accuracy_class(c, 2e-4).has_value());
}
