// Range checks of numeric options, made on the text as typed, so that CLI11 refuses a value
// before the command runs (before any work, any file or device) and the message shows it as
// given: `--seconds 1e400` is named as "1e400", not as the "inf" it converts to.
#pragma once
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

#include "app/whole_number.hpp"
#include "rig/core/escape.hpp"

namespace rig::cli {

// The whole text as a finite decimal number ("+5" as decimal_text takes it), or nothing.
inline std::optional<double> finite_number(const std::string& v) {
  double x = 0;
  const char* const first = v.data() + (v.rfind('+', 0) == 0 ? 1 : 0);
  const auto [end, ec] = std::from_chars(first, v.data() + v.size(), x);
  if (ec != std::errc() || end != v.data() + v.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

// For a decimal number a double cannot hold, what it is, as the readers of records say it:
// " is beyond the range of a double" (1e400) or " is nearer 0 than the smallest double"
// (1e-400, which read "must be a finite number", a review); "" otherwise.
inline std::string range_note(const std::string& v) {
  double x = 0;
  const char* const first = v.data() + (v.rfind('+', 0) == 0 ? 1 : 0);
  const auto [end, ec] = std::from_chars(first, v.data() + v.size(), x);
  if (ec != std::errc::result_out_of_range || end != v.data() + v.size()) return "";
  const double y = std::strtod(std::string(first, end).c_str(), nullptr);  // inf or a tiny/zero value
  return std::fabs(y) > 1 ? " is beyond the range of a double" : " is nearer 0 than the smallest double";
}

// A finite number in [lo, hi] ((lo, hi] when lo_open). `what` says what it is ("a number of
// seconds"). The message: "'TEXT': must be WHAT in (LO, HI]"; CLI11 puts the option's name first.
inline CLI::Validator number_in(double lo, double hi, bool lo_open, const std::string& what) {
  std::ostringstream range;
  range << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  const std::string rule = what + " in " + range.str();
  return CLI::Validator(
      [lo, hi, lo_open, rule](std::string& v) -> std::string {
        const std::optional<double> x = finite_number(v);
        if (x && (lo_open ? *x > lo : *x >= lo) && *x <= hi) return {};
        return "'" + shown_ascii(v) + "'" + range_note(v) + ": must be " + rule;
      },
      "");
}

// Any finite number ("nan", "inf" and "1e400" refused, named as typed).
inline CLI::Validator finite(const std::string& what) {
  return CLI::Validator(
      [what](std::string& v) -> std::string {
        return finite_number(v) ? std::string() : "'" + shown_ascii(v) + "'" + range_note(v) + ": must be " + what;
      },
      "");
}

// A whole number in [least, most], decimal, no sign ("WHAT >= LEAST" when there is no most).
inline CLI::Validator whole_in(const std::string& what, std::uint64_t least,
                               std::uint64_t most = std::numeric_limits<std::uint64_t>::max()) {
  const std::string rule = most == std::numeric_limits<std::uint64_t>::max()
                               ? what + " >= " + std::to_string(least)
                               : what + " in [" + std::to_string(least) + ", " + std::to_string(most) + "]";
  return CLI::Validator(
      [least, most, rule, what](std::string& v) -> std::string {
        if (whole_number(v, least, most)) return std::string();
        if (whole_number_above(v, most))  // "must be >= 1" said of 1e23's digits (a review)
          return "'" + shown_ascii(v) + "' is too large: " + what + " is at most " + std::to_string(most);
        return "'" + shown_ascii(v) + "': must be " + rule + " (decimal, no sign, no leading zero)";
      },
      "");
}

}  // namespace rig::cli
