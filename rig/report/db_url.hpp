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

// An SQLite history's file as it is on disk now (nullopt for PostgreSQL; throws as sqlite_path):
// whether it is there, and if not, whether its folder is (the run would make both). One answer
// for the checks before a run, the dry run's plan and the run's "a new database" note.
struct SqliteFile {
  std::string path;            // as the URL names it
  bool exists = false;         // something is at `path` (not checked to be a database)
  std::string missing_folder;  // the file's folder, absolute, when that is not there either; else ""
};
std::optional<SqliteFile> sqlite_file(const std::string& url);

// postgresql://user:secret@host/db -> postgresql://user:***@host/db (for messages).
std::string mask_password(const std::string& url);

// Whether `url` is one mask_password made (its password read as ***): run.json keeps URLs so,
// and such a URL cannot be opened as it is.
bool password_masked(const std::string& url);

// A URL as a run folder keeps it (run.json's `history_db`): an SQLite file by its absolute path,
// a server's URL with its password masked. Throws as sqlite_path on a bad URL.
std::string kept_form(const std::string& url);

// Whether two URLs name one database however they were written: SQLite files by their resolved
// paths (`h.sqlite`, `sqlite:h.sqlite`, `sqlite:///abs/h.sqlite`, links and "." followed), a
// server's URLs as kept_form gives them (their passwords masked). Throws as sqlite_path.
bool same_database(const std::string& a, const std::string& b);

}  // namespace rig::history
