// What a path a user named is, asked once. std::filesystem's throwing forms end a run with a
// C++ message and exit 4 where the path only cannot be reached (a folder the user may not
// enter: a review ran rig as a non-root user and got "filesystem error: status: Permission
// denied" for a profile, the rig config under $HOME, `rig verify` and `rig history --db`); its
// error_code forms read the same case as "not there". Here it is a configuration error (exit 2)
// naming the path and the system's reason.
#pragma once
#include <filesystem>
#include <string>
#include <system_error>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"

namespace rig {

enum class PathKind { missing, file, directory, other };

// `what` names the path's role in the message ("profile"); empty, the message starts at the path.
inline PathKind path_kind(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  switch (st.type()) {
    case fs::file_type::not_found: return PathKind::missing;  // ENOENT, ENOTDIR
    case fs::file_type::regular: return PathKind::file;
    case fs::file_type::directory: return PathKind::directory;
    case fs::file_type::none:
      throw ConfigError((what.empty() ? "" : what + " ") + shown_text(path) + ": cannot be reached (" + ec.message() +
                        ")");
    default: return PathKind::other;
  }
}

}  // namespace rig
