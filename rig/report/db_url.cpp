#include "rig/report/db_url.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "rig/core/errors.hpp"

namespace rig::history {

std::string mask_password(const std::string& url) {
  const std::size_t scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  std::string out = url;
  const std::size_t start = scheme + 3, end = out.find_first_of("/?", start);
  const std::size_t at = out.rfind('@', end == std::string::npos ? std::string::npos : end);
  if (at != std::string::npos && at >= start) {
    const std::size_t colon = out.find(':', start);
    if (colon != std::string::npos && colon < at) out = out.substr(0, colon + 1) + "***" + out.substr(at);
  }
  // libpq also takes the password as a query parameter (?password=...&...).
  const std::size_t q = out.find('?');
  for (std::size_t p = q; q != std::string::npos && (p = out.find("password=", p)) != std::string::npos;) {
    if (out[p - 1] != '?' && out[p - 1] != '&') {
      ++p;
      continue;
    }
    const std::size_t v = p + 9, e = out.find('&', v);
    out = out.substr(0, v) + "***" + (e == std::string::npos ? "" : out.substr(e));
    p = v + 3;
  }
  return out;
}

namespace {

bool is_postgres(const std::string& url) { return url.rfind("postgresql://", 0) == 0 || url.rfind("postgres://", 0) == 0; }

// The path an SQLite URL names as written: "sqlite:PATH", "sqlite:///abs/path" or a plain path.
std::string written_path(const std::string& url) {
  std::string path = url.rfind("sqlite:", 0) == 0 ? url.substr(7) : url;
  if (path.rfind("//", 0) == 0) path = path.substr(2);
  return path;
}

// A path in the user's home, "~" or "~/...": inside a URL or a config file no shell expands it,
// and "sqlite:~/h.sqlite" made a folder named "~" in the working folder (a review).
bool in_home(const std::string& path) { return path == "~" || path.rfind("~/", 0) == 0; }

const char* home() {
  const char* h = std::getenv("HOME");
  return h && *h ? h : nullptr;
}

// The file an SQLite URL names, "~/" read as $HOME (without $HOME, url_problem says so).
std::string file_part(const std::string& url) {
  const std::string path = written_path(url);
  return in_home(path) && home() ? std::string(home()) + path.substr(1) : path;
}

constexpr const char* kNamesNoFile = "names no file";

}  // namespace

std::string url_problem(const std::string& url) {
  // Blanks at an end are a quoting slip, not a file name: RIG_HISTORY=' ' or --db ' ' opened a
  // file named " " in the working folder, a history nobody reads (a review).
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  if (std::all_of(url.begin(), url.end(), blank)) return "is blank";
  if (blank(url.front()) || blank(url.back()))
    return "begins or ends with a blank (a quoting slip? no history database is named so)";
  if (is_postgres(url)) return "";
  if (file_part(url).empty()) return kNamesNoFile;
  if (in_home(written_path(url)) && !home()) return "starts with ~ and $HOME is not set";
  // "scheme:..." (a colon before any slash) other than sqlite: is a URL this rig cannot open.
  const std::size_t colon = url.find(':');
  if (colon != std::string::npos && colon < url.find('/') && url.rfind("sqlite:", 0) != 0)
    return "unknown scheme (expected sqlite:PATH, a path, or postgresql://...)";
  // SQLite's own names for no file: ":memory:" took the run's row into a database gone when the
  // process ended, said "recorded" and exit 0 (an integrator's review); "file:" URIs and "?"
  // options are not read from the URL (a file named "h.sqlite?x=1" was made).
  const std::string file = file_part(url);
  if (file == ":memory:")
    return "names SQLite's in-memory database, which nothing outlives the process in: give a file";
  if (file.rfind("file:", 0) == 0) return "is an SQLite URI (file:...): give the file's path, sqlite:PATH";
  if (file.find('?') != std::string::npos)
    return "holds '?': options are not read from the URL (a file of that name would be made): give the file's path";
  return "";
}

std::optional<std::string> sqlite_path(const std::string& url) {
  if (const std::string why = url_problem(url); !why.empty())
    throw ConfigError("history database URL '" + mask_password(url) + "'" + (why == kNamesNoFile ? " " : ": ") + why);
  if (is_postgres(url)) return std::nullopt;
  return file_part(url);
}

std::optional<SqliteFile> sqlite_file(const std::string& url) {
  const std::optional<std::string> path = sqlite_path(url);
  if (!path) return std::nullopt;
  namespace fs = std::filesystem;
  std::error_code ec;
  SqliteFile f{*path, fs::exists(*path, ec), ""};
  if (!f.exists) {
    const fs::path folder = fs::absolute(*path, ec).parent_path();
    if (!fs::exists(folder, ec)) f.missing_folder = folder.string();
  }
  return f;
}

bool password_masked(const std::string& url) {
  return url.find(":***@") != std::string::npos || url.find("password=***") != std::string::npos;
}

std::string kept_form(const std::string& url) {
  const std::optional<std::string> file = sqlite_path(url);
  return file ? "sqlite:" + std::filesystem::absolute(*file).lexically_normal().string() : mask_password(url);
}

bool same_database(const std::string& a, const std::string& b) {
  const std::optional<std::string> fa = sqlite_path(a), fb = sqlite_path(b);
  if (fa && fb) {
    std::error_code e1, e2;
    return std::filesystem::weakly_canonical(std::filesystem::absolute(*fa), e1) ==
           std::filesystem::weakly_canonical(std::filesystem::absolute(*fb), e2);
  }
  return kept_form(a) == kept_form(b);
}

}  // namespace rig::history
