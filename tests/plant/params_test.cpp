// The DUT profile: the compiled-in default, overrides, and clear errors.
#include <gtest/gtest.h>

#include "plant/dut/params.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {
namespace {

std::string error_of(const std::string& text) {
  const toml::table t = cfg::parse_string(text, "profiles/x.toml");
  try {
    load_dut_params(&t);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Params, DefaultProfileLoads) {
  const DutParams p = load_dut_params(nullptr);
  EXPECT_EQ(p.loop.loop_rate_hz, 10000);
  EXPECT_EQ(p.loop.output_rate_hz, 1000);
  EXPECT_EQ(p.filter.sections.size(), 1u);
  EXPECT_DOUBLE_EQ(p.filter.sections[0].a1, -1.228261);
  EXPECT_FALSE(p.seed.has_value());
  EXPECT_NE(default_dut_toml().find("[regulator]"), std::string_view::npos);
}

TEST(Params, OverridesApply) {
  const toml::table t = cfg::parse_string(
      "seed = 42\nserial = \"SN-7\"\n[noise]\nenabled = false\n[orientation]\nmisalignment_rad = 1e-3\n"
      "[filter]\npreset = \"custom\"\nsections = [[0.5, 0.5, 0, 0, 0]]\n",
      "p.toml");
  const DutParams p = load_dut_params(&t);
  EXPECT_EQ(p.seed, 42u);
  EXPECT_EQ(p.serial, "SN-7");
  EXPECT_FALSE(p.noise.enabled);
  EXPECT_DOUBLE_EQ(p.orientation.misalignment_rad, 1e-3);
  ASSERT_EQ(p.filter.sections.size(), 1u);
  EXPECT_DOUBLE_EQ(p.filter.sections[0].b1, 0.5);
  EXPECT_DOUBLE_EQ(p.regulator.lead_zero_hz, load_dut_params(nullptr).regulator.lead_zero_hz);
}

TEST(Params, UnknownKeyIsNamedWithItsPosition) {
  const std::string e = error_of("[noise]\nwhite_g = 1\n");
  EXPECT_NE(e.find("profiles/x.toml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("white_g"), std::string::npos) << e;
  EXPECT_NE(error_of("colour = 1\n").find("colour"), std::string::npos);
}

TEST(Params, BadValuesAreRejected) {
  EXPECT_NE(error_of("[loop]\ninertia_kg_m2 = \"heavy\"\n").find("profiles/x.toml:2"), std::string::npos);
  EXPECT_NE(error_of("[loop]\nadc_bits = 2\n").find("adc_bits"), std::string::npos);
  EXPECT_NE(error_of("[loop]\noutput_rate_hz = 3000\n").find("integer multiple"), std::string::npos);
  EXPECT_NE(error_of("[filter]\npreset = \"cheby\"\n").find("cheby"), std::string::npos);
  EXPECT_NE(error_of("[filter]\npreset = \"custom\"\nsections = [[1, 2]]\n").find("[b0, b1, b2, a1, a2]"),
            std::string::npos);
  EXPECT_NE(error_of("[noise]\nflicker_tau_max_s = 0.1\n").find("flicker_tau_max_s"), std::string::npos);
  EXPECT_NE(error_of("[noise]\npolling_drift_tau_s = 0\n").find("polling_drift_tau_s"), std::string::npos);
  EXPECT_NE(error_of("[noise]\npolling_k_g_per_rts = -1e-7\n").find("polling_k_g_per_rts"), std::string::npos);
}

}  // namespace
}  // namespace rig::plant
