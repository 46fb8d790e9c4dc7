#include "rig/report/db_url.hpp"

#include "rig/core/errors.hpp"

namespace rig::history {

std::string mask_password(const std::string& url) {
  const std::size_t scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  const std::size_t start = scheme + 3, end = url.find_first_of("/?", start);
  const std::size_t at = url.rfind('@', end == std::string::npos ? std::string::npos : end);
  if (at == std::string::npos || at < start) return url;
  const std::size_t colon = url.find(':', start);
  if (colon == std::string::npos || colon > at) return url;
  return url.substr(0, colon + 1) + "***" + url.substr(at);
}

namespace {

bool is_postgres(const std::string& url) { return url.rfind("postgresql://", 0) == 0 || url.rfind("postgres://", 0) == 0; }

// The file an SQLite URL names: "sqlite:PATH", "sqlite:///abs/path" or a plain path.
std::string file_part(const std::string& url) {
  std::string path = url.rfind("sqlite:", 0) == 0 ? url.substr(7) : url;
  if (path.rfind("//", 0) == 0) path = path.substr(2);
  return path;
}

constexpr const char* kNamesNoFile = "names no file";

}  // namespace

std::string url_problem(const std::string& url) {
  if (is_postgres(url)) return "";
  if (file_part(url).empty()) return kNamesNoFile;
  // "scheme:..." (a colon before any slash) other than sqlite: is a URL this rig cannot open.
  const std::size_t colon = url.find(':');
  if (colon != std::string::npos && colon < url.find('/') && url.rfind("sqlite:", 0) != 0)
    return "unknown scheme (expected sqlite:PATH, a path, or postgresql://...)";
  return "";
}

std::optional<std::string> sqlite_path(const std::string& url) {
  if (const std::string why = url_problem(url); !why.empty())
    throw ConfigError("history database URL '" + mask_password(url) + "'" + (why == kNamesNoFile ? " " : ": ") + why);
  if (is_postgres(url)) return std::nullopt;
  return file_part(url);
}

}  // namespace rig::history
