// Where a subcommand's output file goes, checked before anything is read or any device asked:
// a measurement or an import is never made only to be lost to a path that cannot be written.
#pragma once
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

#include "app/abort_cleanup.hpp"
#include "rig/core/errors.hpp"

namespace rig::cli {

// Set at start-up (main.cpp) when the process began with stdout closed and it was opened on
// /dev/full: a write there is said as "standard output is closed", not "No space left on device".
inline bool& stdout_closed() {
  static bool closed = false;
  return closed;
}

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

// `st` is the file open on descriptor `fd`.
inline bool open_on(const struct stat& st, int fd) {
  struct stat s {};
  return ::fstat(fd, &s) == 0 && s.st_dev == st.st_dev && s.st_ino == st.st_ino;
}

// The file `path` names, where it is best replaced by a file written beside it and renamed into
// place (its symlinks followed; `path` itself when nothing is there yet): a regular file of one
// name, reached by a plain path. Anything else is written through:
// a device or a pipe; the file behind the process's own stdin, stdout or stderr (`--json
// /dev/stdout > out.txt`: a rename lost the table printed after it, `>>` lost the file's earlier
// lines, a code review); a /proc or /dev name; a file with other hard links (they would keep the
// old text); a dangling symlink (its target is made, as before).
inline std::optional<std::filesystem::path> replace_by_rename(const std::string& path, const struct stat& st, bool exists) {
  if (!exists) {
    struct stat l {};
    if (::lstat(path.c_str(), &l) == 0) return std::nullopt;  // a dangling link is written through
    return std::filesystem::path(path);
  }
  if (!S_ISREG(st.st_mode) || st.st_nlink > 1 || open_on(st, 0) || open_on(st, 1) || open_on(st, 2)) return std::nullopt;
  std::error_code ec;
  std::filesystem::path real = std::filesystem::canonical(path, ec);
  if (ec || real.string().rfind("/proc/", 0) == 0 || real.string().rfind("/dev/", 0) == 0) return std::nullopt;
  return real;
}

// Writes `text` to `path`, every step checked: a JSON nobody gets must not end in exit 0
// (`--json /dev/full` did; a review). ConfigError (exit 2) naming the file and the step that
// failed. A regular file (replace_by_rename) is written beside itself and renamed into place, its
// mode kept, so a write that fails (a full disk) leaves the file as it was, not a cut-off JSON (a
// technician's review); a symlink's file is what is replaced. Where no file can be made beside
// it (a folder that takes no new files, a name too long for a suffix), the file's owner cannot be
// kept (another user's file) or the rename is refused (a sticky folder), and for everything else,
// the file is written through as before.
inline void write_output_file(const std::string& path, const std::string& text, const std::string& what) {
  const auto write_all = [&](int fd) {
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const int e = n < 0 ? errno : EIO;
        ::close(fd);
        return std::string(std::strerror(e));
      }
      done += static_cast<std::size_t>(n);
    }
    return ::close(fd) != 0 ? std::string(std::strerror(errno)) + " (at close)" : std::string();
  };
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  // The command's own stdout or stderr (`--json /dev/stdout`, to a terminal, a pipe or a file):
  // written on that descriptor after what was printed before it, not opened again, which
  // truncated a file the shell appends to (`>>` lost its earlier lines, a code review).
  for (const int out : {1, 2}) {
    if (!exists || !open_on(st, out)) continue;
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    const int fd = ::dup(out);
    const std::string failed = fd < 0 ? std::string(std::strerror(errno)) : write_all(fd);
    if (!failed.empty() && out == 1 && stdout_closed())
      throw ConfigError(what + " " + path + ": standard output is closed (the command was started with it closed, >&-)");
    if (!failed.empty()) throw ConfigError(what + " " + path + ": write failed: " + failed);
    return;
  }
  if (const std::optional<std::filesystem::path> replaced = replace_by_rename(path, st, exists)) {
    const std::filesystem::path& target = *replaced;
    const std::filesystem::path folder = target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
    const std::string staged =
        (folder / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()))).string();
    // A new file's mode as the umask makes it; a file's own kept (the umask cut a 664 file to 644,
    // a code review).
    int fd = ::open(staged.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, exists ? 0600 : 0666);
    // Its owner and group kept too (root's --json over a technician's file made it root's, a
    // review), as the new file came out (a setgid folder gives it the folder's group, a code
    // review); where this account may not give them, the file is written through, as before.
    struct stat made {};
    if (fd >= 0 && exists && ::fstat(fd, &made) == 0 && (made.st_uid != st.st_uid || made.st_gid != st.st_gid) &&
        ::fchown(fd, st.st_uid, st.st_gid) != 0) {
      ::close(fd);
      ::unlink(staged.c_str());
      fd = -1;
    }
    if (fd >= 0) {
      RemoveOnAbort on_signal(staged, "");
      if (exists) ::fchmod(fd, st.st_mode & 07777);
      if (const std::string failed = write_all(fd); !failed.empty()) {
        ::unlink(staged.c_str());
        throw ConfigError(what + " " + path + ": write failed: " + failed +
                          (exists ? " (the file is as it was)" : " (nothing written)"));
      }
      if (::rename(staged.c_str(), target.c_str()) == 0) return;
      ::unlink(staged.c_str());  // refused (a sticky folder's file of another user): written through below
    }
  }
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw ConfigError(what + " " + path + ": cannot open for writing: " + std::strerror(errno));
  // Written in place, a failed write leaves the file cut off: said (a re-test: a hard-linked file
  // was left a cut-off JSON with no word, where a replaced one says "the file is as it was").
  struct stat now {};
  const bool regular = ::fstat(fd, &now) == 0 && S_ISREG(now.st_mode);
  if (const std::string failed = write_all(fd); !failed.empty())
    throw ConfigError(what + " " + path + ": write failed: " + failed +
                      (regular ? " (written in place, as this file could not be replaced: it is now incomplete)" : ""));
}

}  // namespace rig::cli
