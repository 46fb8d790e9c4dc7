// A value quoted with its bounds, written with the digits the bounds support: the half-width
// (hi − lo)/2 rounded to two significant digits, and the value and both bounds rounded to the
// same last digit (JCGM 100:2008, the GUM, 7.2.6). The passport's JSON keeps full precision;
// this is only how a page shows it.
#pragma once
#include <optional>
#include <string>

namespace rig::report {

struct BoundedText {
  std::string value, lo, hi;
};

// nullopt when the bounds give no width (a bound absent or not finite, hi <= lo, or a value
// not finite): the caller keeps its own format then.
std::optional<BoundedText> round_to_bounds(double value, double lo, double hi);

}  // namespace rig::report
