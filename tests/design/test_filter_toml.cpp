// The one [filter] table reader: presets, custom sections, layering onto a default, errors
// naming file:line.
#include <gtest/gtest.h>

#include "design/filter.hpp"
#include "design/filter_toml.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::design {
namespace {

struct Read {
  FilterConfig f;
  std::string preset;
};
Read read(const std::string& text, RateKey rate = RateKey::allowed, FilterConfig base = paper_wf()) {
  const toml::table t = cfg::parse_string(text, "f.toml");
  Read r{base, ""};
  r.preset = read_filter_table(t, "filter", rate, r.f);
  return r;
}
std::string error_of(const std::string& text, RateKey rate = RateKey::allowed) {
  try {
    read(text, rate);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(FilterToml, Presets) {
  FilterConfig none_base;
  none_base.sections.clear();
  const Read p = read("preset = \"paper\"\n", RateKey::allowed, none_base);
  EXPECT_EQ(p.preset, "paper");
  ASSERT_EQ(p.f.sections.size(), 1u);
  EXPECT_EQ(p.f.sections[0].a1, -1.228261);
  EXPECT_EQ(p.f.rate_hz, 10000.0);
  const Read n = read("preset = \"none\"\n");
  EXPECT_EQ(n.preset, "none");
  EXPECT_TRUE(n.f.sections.empty());
  EXPECT_FALSE(n.f.enabled);
}

TEST(FilterToml, CustomSectionsWithOrWithoutThePreset) {
  for (const char* head : {"preset = \"custom\"\n", ""}) {
    const Read c = read(std::string(head) + "sections = [[0.5, 0.5, 0, 0, 0], [1, 0, 0, -0.5, 0]]\nrate_hz = 1000\n");
    EXPECT_EQ(c.preset, "custom");
    ASSERT_EQ(c.f.sections.size(), 2u);
    EXPECT_EQ(c.f.sections[0].b1, 0.5);
    EXPECT_EQ(c.f.sections[1].a1, -0.5);
    EXPECT_EQ(c.f.rate_hz, 1000.0);
    EXPECT_TRUE(c.f.enabled);
  }
}

TEST(FilterToml, WithoutPresetOrSectionsTheBaseStays) {
  const Read r = read("enabled = false\n");
  EXPECT_EQ(r.preset, "");
  ASSERT_EQ(r.f.sections.size(), 1u);
  EXPECT_FALSE(r.f.enabled);
}

TEST(FilterToml, ErrorsNameTheFileAndLine) {
  EXPECT_NE(error_of("preset = \"cheby\"\n").find("f.toml:1"), std::string::npos);
  EXPECT_NE(error_of("preset = \"cheby\"\n").find("cheby"), std::string::npos);
  EXPECT_NE(error_of("preset = \"custom\"\n").find("needs sections"), std::string::npos);
  EXPECT_NE(error_of("sections = [[1, 2]]\n").find("[b0, b1, b2, a1, a2]"), std::string::npos);
  EXPECT_NE(error_of("sections = [[1, 0, 0, \"x\", 0]]\n").find("must be numbers"), std::string::npos);
  EXPECT_NE(error_of("preset = \"paper\"\nsections = [[1, 0, 0, 0, 0]]\n").find("f.toml:2"), std::string::npos);
  EXPECT_NE(error_of("preset = \"paper\"\nrate_hz = 1000\n", RateKey::absent).find("rate_hz"), std::string::npos);
  EXPECT_NE(error_of("presett = \"paper\"\n").find("presett"), std::string::npos);
  // What a DUT would refuse only after power-on is refused here, with its place (a review: an
  // unstable section and coefficients beyond binary32 passed --dry-run).
  EXPECT_EQ(error_of("sections = [[1.0, 0.0, 0.0, -2.5, 1.5]]\n"),
            "f.toml:1:13: filter section [1, 0, 0, -2.5, 1.5] is unstable: its poles (a1, a2) are not inside the unit circle");
  EXPECT_EQ(error_of("sections = [[1e308, 0.0, 0.0, 0.0, 0.0]]\n"),
            "f.toml:1:14: filter coefficient 1e+308 is beyond the protocol's 32-bit float range");
  EXPECT_NE(error_of("sections = [[1.0, 0.0, 0.0, 0.0, nan]]\n").find("f.toml:1:34: filter coefficient nan is not a number"),
            std::string::npos)
      << error_of("sections = [[1.0, 0.0, 0.0, 0.0, nan]]\n");
  EXPECT_NE(error_of("sections = [[1.0, 0.0, 0.0, 0.0, 1.0]]\n").find("unstable"), std::string::npos)
      << "a pole on the unit circle";
  EXPECT_EQ(error_of("sections = [[0.2, 0.0, 0.0, -0.5, 0.1]]\n"), "") << "a stable section";
  // Held as the DUT holds them, in binary32 (as `rig dut set-filter --biquad` is): a coefficient
  // that arrives as 0, a pole the rounding puts on the unit circle.
  EXPECT_EQ(error_of("sections = [[1.0, 1e-50, 0.0, 0.0, 0.0]]\n"),
            "f.toml:1:19: filter coefficient 1e-50 is 0 in the protocol's 32-bit float (nearer 0 than 1.4e-45): give 0, "
            "or a coefficient it holds");
  EXPECT_EQ(error_of("sections = [[1.0, 0.0, 0.0, 0.0, 0.99999999]]\n"),
            "f.toml:1:13: filter section [1, 0, 0, 0, 0.99999999] is unstable: its poles (a1, a2), as the protocol's "
            "32-bit float holds them, are not inside the unit circle");
  // No section, or one that passes nothing (y(t) = 0, rms_filtered passed on it: a review).
  EXPECT_EQ(error_of("preset = \"custom\"\nsections = []\n"),
            "f.toml:2:12: sections = [] has no section; a filter has at least one (enabled = false leaves the filter out)");
  EXPECT_EQ(error_of("sections = [[0.0, 0.0, 0.0, 0.0, 0.0]]\n"),
            "f.toml:1:13: filter section [0, 0, 0, 0, 0] passes nothing (b0 = b1 = b2 = 0): y(t) would be 0; enabled = "
            "false leaves the filter out");
}

}  // namespace
}  // namespace rig::design
