// ISO 8601 times as the history database stores them: UTC, "YYYY-MM-DDTHH:MM:SSZ",
// so that text order is time order in both SQLite and PostgreSQL.
#pragma once
#include <optional>
#include <string>

namespace rig::history {

// "2026-11-22", "2026-11-22T05:12:26", "...26.123Z", "...26+03:00", "... 05:12" (space)
// -> "2026-11-22T02:12:26Z". nullopt if the text is not such a time.
std::optional<std::string> normalize_iso8601(const std::string& text);
// Seconds since the epoch (UTC) of such a time; nullopt if it is not one. A fraction of a second
// is dropped; `fraction` (when given) says whether it had a nonzero one.
std::optional<long long> parse_iso8601(const std::string& text, bool* fraction = nullptr);
// As normalize_iso8601, but a time with a nonzero fraction of a second goes up to the next whole
// second: the history's times are whole seconds, so a bound of 04.9 s compares with them as the
// instant it is (a review: --since ...:04.9 took a run started at :04, --until ...:04.9 left it out).
std::optional<std::string> normalize_iso8601_up(const std::string& text);
// normalize_iso8601_up of an option's value (`option`: "--since"), or ConfigError naming the
// option and the value: the history's query and the command line check bounds by it.
std::string iso8601_bound(const std::string& text, const char* option);
// The current time in that form.
std::string utc_now_iso8601();

}  // namespace rig::history
