// ISO 8601 times as the history database stores them: UTC, "YYYY-MM-DDTHH:MM:SSZ",
// so that text order is time order in both SQLite and PostgreSQL.
#pragma once
#include <optional>
#include <string>

namespace rig::history {

// "2026-11-22", "2026-11-22T05:12:26", "...26.123Z", "...26+03:00", "... 05:12" (space)
// -> "2026-11-22T02:12:26Z". nullopt if the text is not such a time.
std::optional<std::string> normalize_iso8601(const std::string& text);
// Seconds since the epoch (UTC) of such a time; nullopt if it is not one.
std::optional<long long> parse_iso8601(const std::string& text);
// The current time in that form.
std::string utc_now_iso8601();

}  // namespace rig::history
