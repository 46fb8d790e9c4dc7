// The calibration table (docs/plant.md) for the default profile: the paper's whole
// procedure (110 min of DUT time) run on the model and measured by the rig's analysis.
#include <gtest/gtest.h>

#include "plant/dut/loop_figures.hpp"
#include "procedures/analysis/noise_terms.hpp"
#include "tests/plant/paper_procedure.hpp"

namespace rig::plant {
namespace {

class Calibration : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    EmulatedDut dut(load_dut_params(nullptr), 1);
    result_ = new calib::Result(calib::run(dut, calib::Spec{}));
  }
  static void TearDownTestSuite() {
    delete result_;
    result_ = nullptr;
  }
  static calib::Result* result_;
};
calib::Result* Calibration::result_ = nullptr;

TEST_F(Calibration, BiasAndBaseErrorWithinOnePercent) {
  EXPECT_NEAR(result_->bias, -5.0137e-4, 0.01 * 5.0137e-4);
  EXPECT_NEAR(result_->base_error, 3.8549e-4, 0.01 * 3.8549e-4);
  ASSERT_EQ(result_->x10.size(), 6u);
  ASSERT_EQ(result_->x20.size(), 6u);
}

TEST_F(Calibration, InRunBByGost) {
  EXPECT_NEAR(result_->b_gost_100, 4e-6, 0.5 * 4e-6);
}

TEST_F(Calibration, InRunBByAllan) {
  ASSERT_TRUE(result_->nt_x.B.value) << result_->nt_x.B.reason;
  EXPECT_NEAR(*result_->nt_x.B.value, 2.1e-6, 0.3 * 2.1e-6);
}

// The filtered curve flattens from ~16 s to the end of the record with its slope rising
// monotonically, so the paper's quartic has no inflection to bound a flat segment there
// (docs/plant.md); the flat levels are read off the same OADEV curves as sigma_min / 0.664.
TEST_F(Calibration, FilterLowersBByAbout2p5) {
  const double bx = calib::b_from_minimum(result_->adev_x), by = calib::b_from_minimum(result_->adev_y);
  EXPECT_NEAR(bx / by, 2.5, 0.5);
  EXPECT_NEAR(by, 0.86e-6, 0.5 * 0.86e-6);
}

TEST_F(Calibration, QuantisationWithinFactor1p5) {
  ASSERT_TRUE(result_->nt_x.Q.value) << result_->nt_x.Q.reason;
  const double q = analysis::q_per_hour(*result_->nt_x.Q.value);
  EXPECT_GT(q, 6.3603e-10 / 1.5);
  EXPECT_LT(q, 6.3603e-10 * 1.5);
}

// Known miss (docs/plant.md): the weighted fit's N is set by the 1-30 ms points, where the
// velocity quantiser and the folded tones do not follow the Q + N model; it lands about
// 1.7x the paper's. Held within 2x so that a regression still fails.
TEST_F(Calibration, RandomWalkWithinFactor2) {
  ASSERT_TRUE(result_->nt_x.N.value) << result_->nt_x.N.reason;
  const double n = analysis::n_per_hour(*result_->nt_x.N.value);
  EXPECT_GT(n, 2.2306e-7 / 2);
  EXPECT_LT(n, 2.2306e-7 * 2);
}

TEST_F(Calibration, RateRampNotDeterminableFromOneHour) {
  EXPECT_FALSE(result_->nt_x.R.value.has_value());
}

TEST(CalibrationLoop, SettlingAndBandwidth) {
  const LoopFigures f = loop_figures(nullptr, paper_filter());
  EXPECT_NEAR(f.settling_time_s, 0.003, 0.2 * 0.003);
  EXPECT_NEAR(f.bandwidth_0p5_hz, 492, 0.05 * 492);
}

}  // namespace
}  // namespace rig::plant
