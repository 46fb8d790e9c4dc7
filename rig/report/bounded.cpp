#include "rig/report/bounded.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace rig::report {

namespace {

// The decimal exponent of the last digit kept: the half-width is first rounded to two
// significant digits ("%.1e" does it, 9.96e-7 -> 1.0e-06), and its second digit is the last.
int last_digit_exponent(double half_width) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1e", half_width);
  const char* e = std::strchr(buf, 'e');
  return (e ? std::atoi(e + 1) : 0) - 1;
}

// x rounded to a multiple of 10^e and written down to that digit: fixed notation for
// magnitudes 1e-4 ... 1e6 (as the page's other numbers), else d.ddde±XX with as many digits.
std::string write_to_digit(double x, int e) {
  const double n = std::round(x / std::pow(10.0, e));  // an integer count of 10^e
  if (n == 0) return "0";
  int digits = 1;  // of |n|, counted exactly (no log10 at a power of ten)
  for (double m = std::abs(n); m >= 10; m = std::floor(m / 10)) ++digits;
  const int exponent = e + digits - 1;  // of the rounded value's first digit
  const double r = n * std::pow(10.0, e);
  char buf[48];
  if (exponent >= -4 && exponent < 6)
    std::snprintf(buf, sizeof buf, "%.*f", e < 0 ? -e : 0, r);
  else
    std::snprintf(buf, sizeof buf, "%.*e", digits - 1, r);
  return buf;
}

}  // namespace

std::optional<BoundedText> round_to_bounds(double value, double lo, double hi) {
  if (!std::isfinite(value) || !std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo)) return std::nullopt;
  const double half = (hi - lo) / 2;
  if (!std::isfinite(half) || half <= 0) return std::nullopt;
  const int e = last_digit_exponent(half);
  // A value that is huge next to its width would need more than a double's digits.
  for (double x : {value, lo, hi})
    if (std::abs(x) / std::pow(10.0, e) > 1e15) return std::nullopt;
  return BoundedText{write_to_digit(value, e), write_to_digit(lo, e), write_to_digit(hi, e)};
}

}  // namespace rig::report
