// The calibration table (docs/plant.md) for the default profile: the paper's whole
// procedure (110 min of DUT time) run on the model and measured by the rig's analysis.
#include <gtest/gtest.h>

#include "plant/dut/loop_figures.hpp"
#include "procedures/analysis/noise_terms.hpp"
#include "tests/plant/paper_procedure.hpp"

namespace rig::plant {
namespace {

// One run (about 3 s of CPU in RelWithDebInfo) checked against every row of the table;
// ctest runs each test in its own process, so the rows share one test.
TEST(Calibration, PaperTableForTheDefaultProfile) {
  EmulatedDut dut(load_dut_params(nullptr), 1);
  const calib::Result r = calib::run(dut, calib::Spec{});
  ASSERT_EQ(r.x10.size(), 6u);
  ASSERT_EQ(r.x20.size(), 6u);
  {
    SCOPED_TRACE("bias and base error within 1 %");
    EXPECT_NEAR(r.bias, -5.0137e-4, 0.01 * 5.0137e-4);
    EXPECT_NEAR(r.base_error, 3.8549e-4, 0.01 * 3.8549e-4);
  }
  {
    SCOPED_TRACE("in-run B by GOST, 100 s, within 50 %");
    EXPECT_NEAR(r.b_gost_100, 4e-6, 0.5 * 4e-6);
  }
  {
    SCOPED_TRACE("in-run B by Allan within 30 %");
    ASSERT_TRUE(r.nt_x.B.value) << r.nt_x.B.reason;
    EXPECT_NEAR(*r.nt_x.B.value, 2.1e-6, 0.3 * 2.1e-6);
  }
  {
    // The paper's 2.5x lower B with the output filter. Measured (docs/plant.md): 1.9 (seed 1),
    // 2.2 (seed 2): the folded 1 kHz pick-up is cut by |W_f(1 kHz)| = 0.39, but the rate random
    // walk K (held within 1.5x of the paper's) is not filtered and sets a floor under B_y.
    // Held at [1.5, 3.0] and B_y within 50 % of 0.86e-6 so a broken mechanism still fails.
    SCOPED_TRACE("B with the filter");
    const double by = r.nt_y.B.value ? *r.nt_y.B.value : calib::b_from_minimum(r.adev_y);
    const double ratio = r.nt_x.B.value.value_or(0) / by;
    EXPECT_GE(ratio, 1.5);
    EXPECT_LE(ratio, 3.0);
    EXPECT_NEAR(by, 0.86e-6, 0.5 * 0.86e-6);
  }
  {
    SCOPED_TRACE("Q and N within a factor of 1.5");
    ASSERT_TRUE(r.nt_x.Q.value) << r.nt_x.Q.reason;
    ASSERT_TRUE(r.nt_x.N.value) << r.nt_x.N.reason;
    const double q = analysis::q_per_hour(*r.nt_x.Q.value), n = analysis::n_per_hour(*r.nt_x.N.value);
    EXPECT_GT(q, 6.3603e-10 / 1.5);
    EXPECT_LT(q, 6.3603e-10 * 1.5);
    EXPECT_GT(n, 2.2306e-7 / 1.5);
    EXPECT_LT(n, 2.2306e-7 * 1.5);
  }
  {
    SCOPED_TRACE("R is not determinable from one hour");
    EXPECT_FALSE(r.nt_x.R.value.has_value());
  }
}

TEST(CalibrationLoop, SettlingAndBandwidth) {
  const LoopFigures f = loop_figures(nullptr, paper_filter());
  EXPECT_NEAR(f.settling_time_s, 0.003, 0.2 * 0.003);
  EXPECT_NEAR(f.bandwidth_0p5_hz, 492, 0.05 * 492);
}

}  // namespace
}  // namespace rig::plant
