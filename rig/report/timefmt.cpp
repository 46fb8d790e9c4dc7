#include "rig/report/timefmt.hpp"

#include "rig/core/errors.hpp"

#include <cstdio>
#include <ctime>

namespace rig::history {

namespace {
std::string format_utc(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}
}  // namespace

std::optional<long long> parse_iso8601(const std::string& text, bool* fraction) {
  if (fraction) *fraction = false;
  // YYYY-MM-DD[(T| )HH:MM[:SS[(.|,)fraction]]][Z|±HH[:]MM], surrounding blanks allowed.
  // (Hand-written: std::regex trips GCC 12's -Wmaybe-uninitialized under the sanitizers.)
  std::size_t i = text.find_first_not_of(" \t");
  std::size_t end = text.find_last_not_of(" \t");
  if (i == std::string::npos) return std::nullopt;
  const std::string s = text.substr(i, end - i + 1);
  std::size_t p = 0;
  auto digits = [&](int n, int& out) {
    if (p + static_cast<std::size_t>(n) > s.size()) return false;
    out = 0;
    for (int k = 0; k < n; ++k, ++p) {
      if (s[p] < '0' || s[p] > '9') return false;
      out = out * 10 + (s[p] - '0');
    }
    return true;
  };
  auto lit = [&](char c) {
    if (p < s.size() && s[p] == c) {
      ++p;
      return true;
    }
    return false;
  };
  int y = 0, mo = 0, d = 0, hh = 0, mi = 0, ss = 0;
  if (!digits(4, y) || !lit('-') || !digits(2, mo) || !lit('-') || !digits(2, d)) return std::nullopt;
  if (p < s.size() && (s[p] == 'T' || s[p] == ' ')) {
    ++p;
    if (!digits(2, hh) || !lit(':') || !digits(2, mi)) return std::nullopt;
    if (lit(':')) {
      if (!digits(2, ss)) return std::nullopt;
      if (lit('.') || lit(',')) {
        const std::size_t f = p;
        bool nonzero = false;
        for (; p < s.size() && s[p] >= '0' && s[p] <= '9'; ++p) nonzero = nonzero || s[p] != '0';
        if (p == f) return std::nullopt;
        if (fraction) *fraction = nonzero;
      }
    }
  }
  long offset = 0;
  if (p < s.size() && (s[p] == 'Z' || s[p] == 'z')) {
    ++p;
  } else if (p < s.size() && (s[p] == '+' || s[p] == '-')) {
    const bool plus = s[p++] == '+';
    int oh = 0, om = 0;
    if (!digits(2, oh)) return std::nullopt;
    lit(':');
    if (!digits(2, om) || oh > 23 || om > 59) return std::nullopt;
    offset = (plus ? 1 : -1) * (oh * 60L + om) * 60L;
  }
  if (p != s.size()) return std::nullopt;
  std::tm tm{};
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = hh;
  tm.tm_min = mi;
  tm.tm_sec = ss;
  if (mo < 1 || mo > 12 || d < 1 || d > 31 || hh > 23 || mi > 59 || ss > 60) return std::nullopt;
  // A day the month does not have (2026-02-30, 2025-02-29): timegm would roll it into the next
  // month (a review: --since 2026-02-30 was taken as 2026-03-02).
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (d > kDays[mo - 1] + (mo == 2 && leap ? 1 : 0)) return std::nullopt;
  const std::time_t t = timegm(&tm) - offset;
  return static_cast<long long>(t);
}

std::optional<std::string> normalize_iso8601(const std::string& text) {
  const auto t = parse_iso8601(text);
  if (!t) return std::nullopt;
  return format_utc(static_cast<std::time_t>(*t));
}

std::optional<std::string> normalize_iso8601_up(const std::string& text) {
  bool fraction = false;
  const auto t = parse_iso8601(text, &fraction);
  if (!t) return std::nullopt;
  return format_utc(static_cast<std::time_t>(*t + (fraction ? 1 : 0)));
}

std::string utc_now_iso8601() { return format_utc(std::time(nullptr)); }

std::string iso8601_bound(const std::string& text, const char* option) {
  if (auto n = normalize_iso8601_up(text)) return *n;
  throw ConfigError(std::string(option) + " '" + text + "' is not an ISO 8601 date (YYYY-MM-DD[THH:MM[:SS[.FFF]]][Z|+HH:MM])");
}

}  // namespace rig::history
