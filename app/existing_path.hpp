// CLI11 validators for an option naming a file or folder that must exist. CLI11's own
// (ExistingFile, ExistingDirectory) say "does not exist" for a path the user may not reach;
// these say why (rig/core/path_kind.hpp), in CLI11's words otherwise, so the messages
// automation matches on stay.
#pragma once
#include <string>

#include <CLI/CLI.hpp>

#include "rig/core/path_kind.hpp"

namespace rig::cli {

inline CLI::Validator existing_path(PathKind want) {
  const bool file = want == PathKind::file;
  return CLI::Validator(
      [want, file](std::string& p) -> std::string {
        try {
          const PathKind k = path_kind(p, "");
          if (k == want) return "";
          if (k == PathKind::missing) return std::string(file ? "File" : "Directory") + " does not exist: " + p;
          return std::string(file ? "Not a regular file: " : "Not a directory: ") + p;
        } catch (const ConfigError& e) {
          return e.what();
        }
      },
      file ? "FILE" : "DIR");
}

inline CLI::Validator existing_file() { return existing_path(PathKind::file); }
inline CLI::Validator existing_folder() { return existing_path(PathKind::directory); }

}  // namespace rig::cli
