#pragma once
// A history database's URL read without opening anything: the checks every command makes
// before it runs (rig run's --db, a hardware file's [history] url), with no SQLite or libpq.

#include <optional>
#include <string>

namespace rig::history {

// Why rig cannot open `url` ("names no file", "unknown scheme (...)"), or "" when it can try.
std::string url_problem(const std::string& url);

// The file of an SQLite URL (nullopt for PostgreSQL); throws rig::ConfigError on a bad URL
// (another scheme, no file).
std::optional<std::string> sqlite_path(const std::string& url);

// postgresql://user:secret@host/db -> postgresql://user:***@host/db (for messages).
std::string mask_password(const std::string& url);

}  // namespace rig::history
