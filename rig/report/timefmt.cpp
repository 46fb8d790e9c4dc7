#include "rig/report/timefmt.hpp"

#include <cstdio>
#include <ctime>
#include <regex>

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

std::optional<std::string> normalize_iso8601(const std::string& text) {
  static const std::regex re(
      R"(^\s*(\d{4})-(\d{2})-(\d{2})(?:[T ](\d{2}):(\d{2})(?::(\d{2})(?:[.,]\d+)?)?)?\s*(Z|z|[+-]\d{2}:?\d{2})?\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re)) return std::nullopt;
  auto num = [&](int i) { return m[i].matched ? std::stoi(m[i].str()) : 0; };
  std::tm tm{};
  tm.tm_year = num(1) - 1900;
  tm.tm_mon = num(2) - 1;
  tm.tm_mday = num(3);
  tm.tm_hour = num(4);
  tm.tm_min = num(5);
  tm.tm_sec = num(6);
  if (tm.tm_mon < 0 || tm.tm_mon > 11 || tm.tm_mday < 1 || tm.tm_mday > 31 || tm.tm_hour > 23 || tm.tm_min > 59 ||
      tm.tm_sec > 60)
    return std::nullopt;
  std::time_t t = timegm(&tm);
  if (m[7].matched && m[7].str() != "Z" && m[7].str() != "z") {
    const std::string z = m[7].str();  // ±HH:MM or ±HHMM
    const int hh = std::stoi(z.substr(1, 2)), mm = std::stoi(z.substr(z.size() - 2));
    const long off = (hh * 60L + mm) * 60L;
    t -= z[0] == '+' ? off : -off;
  }
  return format_utc(t);
}

std::string utc_now_iso8601() { return format_utc(std::time(nullptr)); }

}  // namespace rig::history
