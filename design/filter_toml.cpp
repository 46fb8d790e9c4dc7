#include "design/filter_toml.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <optional>

#include "design/filter.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::design {
namespace {

std::string num(double v) {  // the shortest decimal that reads back to v
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::vector<Biquad> read_sections(const toml::node& n) {
  const toml::array* arr = n.as_array();
  if (!arr) throw ConfigError(cfg::where(n) + ": sections = [[b0, b1, b2, a1, a2], ...]");
  // No section is no filter: sections = [] ran as "0 section(s)" (a review); enabled = false says it.
  if (arr->empty())
    throw ConfigError(cfg::where(n) + ": sections = [] has no section; a filter has at least one (enabled = false "
                      "leaves the filter out)");
  std::vector<Biquad> out;
  for (const toml::node& e : *arr) {
    const toml::array* s = e.as_array();
    if (!s || s->size() != 5) throw ConfigError(cfg::where(e) + ": a filter section is [b0, b1, b2, a1, a2]");
    double c[5];
    for (std::size_t i = 0; i < 5; ++i) {
      const std::optional<double> v = (*s)[i].value<double>();
      if (!v) throw ConfigError(cfg::where((*s)[i]) + ": filter coefficients must be numbers");
      // Sent as IEEE binary32 (docs/can-protocol.md): beyond its range a coefficient would arrive as inf.
      if (!(std::abs(*v) <= std::numeric_limits<float>::max()))
        throw ConfigError(cfg::where((*s)[i]) + ": filter coefficient " + num(*v) +
                          (std::isnan(*v) ? " is not a number" : " is beyond the protocol's 32-bit float range"));
      // Nearer 0 than binary32 holds (1.4e-45) it would arrive as 0, as `rig dut set-filter
      // --biquad` refuses it (a review: the profile's sections were held to the double only).
      if (*v != 0 && static_cast<float>(*v) == 0)
        throw ConfigError(cfg::where((*s)[i]) + ": filter coefficient " + num(*v) +
                          " is 0 in the protocol's 32-bit float (nearer 0 than 1.4e-45): give 0, or a coefficient it holds");
      c[i] = *v;
    }
    const Biquad b{c[0], c[1], c[2], c[3], c[4]};
    // A section whose numerator is all zero passes nothing: y(t) = 0, and rms_filtered passed on
    // it (a review). "enabled = false" is how a filter is left out.
    if (c[0] == 0 && c[1] == 0 && c[2] == 0)
      throw ConfigError(cfg::where(e) + ": filter section [" + num(c[0]) + ", " + num(c[1]) + ", " + num(c[2]) + ", " +
                        num(c[3]) + ", " + num(c[4]) + "] passes nothing (b0 = b1 = b2 = 0): y(t) would be 0; "
                        "enabled = false leaves the filter out");
    // Checked here, before any device opens: a DUT refuses an unstable section only after power-on.
    // And as the DUT holds it: a1 = 0.99999999 is stable as a double and on the unit circle in binary32.
    const Biquad sent{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]),
                      static_cast<float>(c[3]), static_cast<float>(c[4])};
    if (!stable_section(b) || !stable_section(sent))
      throw ConfigError(cfg::where(e) + ": filter section [" + num(c[0]) + ", " + num(c[1]) + ", " + num(c[2]) + ", " + num(c[3]) +
                        ", " + num(c[4]) + "] is unstable: its poles (a1, a2)" +
                        (stable_section(b) ? ", as the protocol's 32-bit float holds them," : "") +
                        " are not inside the unit circle");
    out.push_back(b);
  }
  return out;
}

}  // namespace

std::string read_filter_table(const toml::table& t, std::string_view ctx, RateKey rate, FilterConfig& f) {
  if (rate == RateKey::allowed)
    cfg::check_keys(t, {"preset", "sections", "enabled", "rate_hz"}, ctx);
  else
    cfg::check_keys(t, {"preset", "sections", "enabled"}, ctx);
  const toml::node* secs = t.get("sections");
  const std::string preset = cfg::get_string(t, "preset", std::string(secs ? "custom" : ""));
  if (preset == "paper") {
    f = paper_wf();
  } else if (preset == "none") {
    f.sections.clear();
    f.enabled = false;
  } else if (preset == "custom") {
    if (!secs) throw ConfigError(cfg::where(t) + ": preset = \"custom\" needs sections = [[b0, b1, b2, a1, a2], ...]");
    f.sections = read_sections(*secs);
    f.enabled = true;
  } else if (!preset.empty()) {
    throw ConfigError(cfg::where(*t.get("preset")) + ": filter preset must be \"paper\", \"none\" or \"custom\", not \"" +
                      preset + "\"");
  }
  if (secs && preset != "custom")
    throw ConfigError(cfg::where(*secs) + ": sections go with preset = \"custom\", not \"" + preset + "\"");
  if (rate == RateKey::allowed) f.rate_hz = cfg::get_number(t, "rate_hz", f.rate_hz, 1.0, 1e7);
  f.enabled = cfg::get_bool(t, "enabled", f.enabled);
  return preset;
}

}  // namespace rig::design
