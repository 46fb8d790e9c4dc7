// The RMS error of criterion 1 (the filter's own tests are in tests/design).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/rms.hpp"

namespace rig::analysis {
namespace {

TEST(Rms, IsTheRootOfTheMeanSquare) {
  EXPECT_NEAR(rms(std::vector<double>({3.0, 4.0})), std::sqrt(12.5), 1e-12);
  EXPECT_NEAR(rms(std::vector<double>({-2.0, -2.0, 2.0})), 2.0, 1e-12);
  EXPECT_EQ(rms(std::vector<double>()), 0.0);
}

}  // namespace
}  // namespace rig::analysis
