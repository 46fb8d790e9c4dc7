// A double in a message as its shortest text that reads back to the same double (C++17
// std::to_chars): the digits a user typed, not toml++'s 17 nor a stream's 6.
#pragma once
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

namespace rig {

inline std::string shortest_text(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

// A value and its limits as a passport shows them side by side: `digits` significant digits,
// unless that puts them, read back, in another order than the doubles (a failure "0.00314
// outside [0, 0.00314]", a review; a pass 0.0024224 beside [0, 0.00242], a metrologist's
// review), then every digit the doubles hold (shortest_text). One rule for the console, JUnit
// and report.html.
struct ShownOutside {
  std::string value, lo, hi;
};

// Whether the texts, read back (locale-free), stand in the order of value, lo and hi: at or
// above lo, at or below hi, as the numbers are. A text that does not read back is not in order.
inline bool shown_in_order(const ShownOutside& s, double value, double lo, double hi) {
  const auto back = [](const std::string& t) {
    double x = std::nan("");
    std::from_chars(t.data(), t.data() + t.size(), x);
    return x;
  };
  const double v = back(s.value), l = back(s.lo), h = back(s.hi);
  if (std::isnan(v) || std::isnan(l) || std::isnan(h)) return false;
  return (v >= l) == (value >= lo) && (v <= h) == (value <= hi);
}

inline ShownOutside shown_against_limits(double value, double lo, double hi, int digits = 6) {
  const auto some = [digits](double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%.*g", digits, x);
    return std::string(b);
  };
  ShownOutside s{some(value), some(lo), some(hi)};
  if (!shown_in_order(s, value, lo, hi)) s = {shortest_text(value), shortest_text(lo), shortest_text(hi)};
  return s;
}

// A value outside its limits (the name its callers have used).
inline ShownOutside shown_outside(double value, double lo, double hi, int digits = 6) {
  return shown_against_limits(value, lo, hi, digits);
}

}  // namespace rig
