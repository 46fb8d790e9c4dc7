// Where a subcommand's output file goes, checked before anything is read or any device asked:
// a measurement or an import is never made only to be lost to a path that cannot be written.
#pragma once
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "rig/core/errors.hpp"

namespace rig::cli {

// `path` can be replaced by write_file_atomic: its folder exists and takes new files, and what
// lies there now, if anything, is a regular file. ConfigError (exit 2) naming it otherwise.
inline void check_writable_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ConfigError(what + " " + path + ": the folder " + dir.string() + " does not exist");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw ConfigError(what + " " + path + ": cannot create files in " + dir.string());
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw ConfigError(what + " " + path + ": not a regular file (the records replace it)");
}

// As check_writable_file, and nothing may lie at `path` yet: a file that holds data (a capture,
// a record) is not replaced by a command run twice.
inline void check_new_file(const std::string& path, const std::string& what) {
  check_writable_file(path, what);
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0)
    throw ConfigError(what + " " + path + ": the file exists (remove it or choose another name; nothing was read)");
}

}  // namespace rig::cli
