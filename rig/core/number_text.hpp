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

// A value outside its limits and the limits as a failure shows them: `digits` significant
// digits, unless that rounds the value onto or inside its limits ("0.00314 outside [0,
// 0.00314]", a review), then every digit the doubles hold (shortest_text). One rule for the
// console, JUnit and report.html.
struct ShownOutside {
  std::string value, lo, hi;
};
inline ShownOutside shown_outside(double value, double lo, double hi, int digits = 6) {
  const auto some = [digits](double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%.*g", digits, x);
    return std::string(b);
  };
  const auto back = [](const std::string& t) {  // as shown (locale-free); nan reads as nan
    double x = std::nan("");
    std::from_chars(t.data(), t.data() + t.size(), x);
    return x;
  };
  ShownOutside s{some(value), some(lo), some(hi)};
  const double v = back(s.value), l = back(s.lo), h = back(s.hi);
  if (v >= l && v <= h) s = {shortest_text(value), shortest_text(lo), shortest_text(hi)};
  return s;
}

}  // namespace rig
