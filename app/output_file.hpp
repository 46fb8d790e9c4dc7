// Where a subcommand's output file goes, checked before anything is read or any device asked:
// a measurement or an import is never made only to be lost to a path that cannot be written.
#pragma once
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

#include "rig/core/errors.hpp"

namespace rig::cli {

// The folder `path` goes into exists and takes new files. ConfigError (exit 2) naming it otherwise.
inline void check_output_folder(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ConfigError(what + " " + path + ": the folder " + dir.string() + " does not exist");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw ConfigError(what + " " + path + ": cannot create files in " + dir.string());
}

// `path` can be replaced by write_file_atomic: its folder takes new files, and what lies there
// now, if anything, is a regular file. ConfigError (exit 2) naming it otherwise.
inline void check_writable_file(const std::string& path, const std::string& what) {
  check_output_folder(path, what);
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw ConfigError(what + " " + path + ": not a regular file (the records replace it)");
}

// A file written through (opened and truncated, as std::ofstream does; a device or a pipe may
// take it), not replaced: what lies at `path` now, if anything, is no folder and its own
// permission decides (/dev/stdout, a writable file in a read-only folder; a code review), else
// its folder exists and takes new files (a symlink is followed). ConfigError naming it otherwise.
inline void check_output_file(const std::string& path, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw ConfigError(what + " " + path + ": a folder, not a file (give a file name)");
    if (::access(path.c_str(), W_OK) != 0)
      throw ConfigError(what + " " + path + ": cannot be written: " + std::strerror(errno));
    return;
  }
  check_output_folder(path, what);
}

// Whether `path` is the regular file `input` names, by device and inode (through a symlink, "./"
// or another spelling of it); `input` "-" is standard input, by the file it reads, if a file.
inline bool same_regular_file(const std::string& path, const std::string& input) {
  struct stat out {}, in {};
  if (::stat(path.c_str(), &out) != 0) return false;
  if ((input == "-" ? ::fstat(STDIN_FILENO, &in) : ::stat(input.c_str(), &in)) != 0) return false;
  return S_ISREG(in.st_mode) && out.st_dev == in.st_dev && out.st_ino == in.st_ino;
}

// As check_writable_file, and nothing may lie at `path` yet: a file that holds data (a capture,
// a record) is not replaced by a command run twice.
inline void check_new_file(const std::string& path, const std::string& what) {
  check_writable_file(path, what);
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0)
    throw ConfigError(what + " " + path + ": the file exists (remove it or choose another name; nothing was read)");
}

// Writes `text` to `path` through (a device or a pipe included), every step checked: a JSON
// nobody gets must not end in exit 0 (`--json /dev/full` did; a review). ConfigError (exit 2)
// naming the file and the step that failed.
inline void write_output_file(const std::string& path, const std::string& text, const std::string& what) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw ConfigError(what + " " + path + ": cannot open for writing: " + std::strerror(errno));
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n < 0 ? errno : EIO;
      ::close(fd);
      throw ConfigError(what + " " + path + ": write failed: " + std::strerror(e));
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) throw ConfigError(what + " " + path + ": write failed at close: " + std::strerror(errno));
}

}  // namespace rig::cli
