#include "app/table_lock.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>

#include "app/folder_lock.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"

namespace rig::cli {

namespace {
namespace fs = std::filesystem;

std::string lock_folder() {
  if (const char* d = std::getenv("RIG_LOCK_DIR"); d && *d) return d;
  if (::access("/run/lock", W_OK | X_OK) == 0) return "/run/lock";
  std::error_code ec;
  const fs::path t = fs::temp_directory_path(ec);
  return ec ? std::string("/tmp") : t.string();
}

// Who holds it, from the holder's line ("pid 1234: rig run --out ..."). A line whose process is
// gone was left by a holder that could not write its own (a read-only file): not named.
std::string read_holder(int fd) {
  std::string text(512, '\0');
  const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
  text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  if (const auto nl = text.find('\n'); nl != std::string::npos) text.resize(nl);
  const long pid = text.rfind("pid ", 0) == 0 ? std::strtol(text.c_str() + 4, nullptr, 10) : 0;
  if (pid <= 0 || (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)) return "another rig process";
  return shown_text(text);
}

ConfigError planted(const std::string& identity, const std::string& path, const char* what) {
  return ConfigError("table " + identity + ": the lock file " + path + " is " + what +
                     ", which rig does not use; remove it (something other than rig put it there)");
}

// Opens the lock file as a plain file of its own: a symlink is not followed (root would truncate
// its target), a FIFO does not block the open, and a hard link (another file's contents) or
// anything but a regular file is refused. -1 with `why` set where it cannot be opened at all.
// `create` false (a dry run's check, which touches nothing): a missing file is -1 with no reason.
// Open flags of the station's own files (the lock, the stop note): no symlink followed, no FIFO
// waited on.
constexpr int kSafe = O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK;

// nullptr when `fd` is a regular file of its own; else what it is ("a hard link to another file",
// "not a regular file"): a file planted in the shared folder.
const char* not_its_own(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return "not a regular file";
  return st.st_nlink != 1 ? "a hard link to another file" : nullptr;
}

int open_lock_file(const std::string& identity, const std::string& path, std::string& why, bool create = true) {
  int fd = ::open(path.c_str(), O_RDWR | (create ? O_CREAT : 0) | kSafe, 0644);
  int err = errno;
  // Read-only still locks (a file another account made); it cannot say who holds it. Where that
  // fails too, the first refusal is the reason (a read-only folder read "No such file": a re-test).
  if (fd < 0 && err == EACCES) {
    fd = ::open(path.c_str(), O_RDONLY | kSafe);
    if (fd < 0 && errno != ENOENT) err = errno;
  }
  if (fd < 0) {
    struct stat st {};
    if (err == ELOOP) throw planted(identity, path, "a symbolic link");
    if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) throw planted(identity, path, "not a regular file");
    if (!create && err == ENOENT) return -1;
    why = "cannot open the lock file " + path + ": " + std::strerror(err);
    return -1;
  }
  if (const char* what = not_its_own(fd)) {
    ::close(fd);
    throw planted(identity, path, what);
  }
  return fd;
}

// The stop note's file: the lock's name with `.stop` for `.lock`.
std::string stop_note_path(const std::string& identity) {
  const std::string lock = TableLock::path_for(identity);
  return lock.substr(0, lock.size() - 5) + ".stop";
}

// Opens the stop note as a plain file of its own, as the lock file is (no symlink followed, no FIFO
// waited on, no hard link); -1 otherwise, said by nobody: a note is a courtesy, never a fault.
int open_note(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | kSafe, 0644);
  if (fd < 0) return -1;
  if (not_its_own(fd)) {
    ::close(fd);
    errno = 0;  // not a file of its own (planted): said as such by the caller
    return -1;
  }
  return fd;
}

long long epoch_ns(std::chrono::system_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

InUseError in_use(const std::string& identity, const std::string& path, int fd) {
  return InUseError("table " + identity + ": in use by " + read_holder(fd) + " on this station (lock " + path +
                    "); wait for it to end. `rig table stop` and `rig table quick-stop` still reach the drive");
}
}  // namespace

std::string TableLock::path_for(const std::string& identity) {
  std::string name = "rig-table-";
  for (const char c : identity) name += std::isalnum(static_cast<unsigned char>(c)) || c == '.' ? c : '_';
  return (fs::path(lock_folder()) / (name + ".lock")).string();
}

TableLock::TableLock(const std::string& identity, const std::string& holder) {
  const std::string path = path_for(identity);
  const int fd = open_lock_file(identity, path, unlocked_reason_);
  if (fd < 0) return;
  if (const int err = flock_with_retries(fd, LOCK_EX)) {
    if (err != EWOULDBLOCK) {  // a file system without flock
      ::close(fd);
      unlocked_reason_ = "the lock file " + path + " cannot be locked: " + std::strerror(err);
      return;
    }
    const InUseError e = in_use(identity, path, fd);
    ::close(fd);
    throw e;
  }
  fd_ = fd;
  const std::string line = "pid " + std::to_string(::getpid()) + ": " + holder + "\n";
  if (::ftruncate(fd_, 0) == 0) (void)!::pwrite(fd_, line.data(), line.size(), 0);
}

TableLock::~TableLock() {
  if (fd_ < 0) return;
  // Emptied before it is released: a later reader never names a holder that has gone.
  (void)!::ftruncate(fd_, 0);
  ::close(fd_);
}

std::string TableLock::note_stop(const std::string& identity, const std::string& what) {
  const std::string path = stop_note_path(identity);
  const int fd = open_note(path, O_WRONLY | O_CREAT);
  if (fd < 0) return "cannot write " + path + (errno ? std::string(": ") + std::strerror(errno) : std::string());
  // "<ns since the epoch> pid <pid>: <what>": written over the old line, then cut to its length, so
  // a reader meanwhile finds one whole line (the old or the new), never an empty file.
  const std::string line = std::to_string(epoch_ns(std::chrono::system_clock::now())) + " pid " +
                           std::to_string(::getpid()) + ": " + what + "\n";
  std::string problem;
  if (::pwrite(fd, line.data(), line.size(), 0) == static_cast<ssize_t>(line.size()))
    (void)!::ftruncate(fd, static_cast<off_t>(line.size()));
  else
    problem = "cannot write " + path + ": " + std::strerror(errno);
  ::close(fd);
  return problem;
}

std::optional<std::string> TableLock::stop_noted_since(const std::string& identity,
                                                       std::chrono::system_clock::time_point since,
                                                       std::chrono::milliseconds wait) {
  const std::string path = stop_note_path(identity);
  const auto deadline = std::chrono::steady_clock::now() + wait;
  // A stop that halted this motion was answered a poll or two before the halt was seen here (on a
  // loaded machine, seconds), and its note follows within `wait`: one older than 5 s was another
  // motion's stop (a re-test: a stop of this station halting another station's move, then taken
  // for the halt of this one), and one from the future is no stop's (a clock stepped back, a
  // planted file).
  const auto now = std::chrono::system_clock::now();
  const long long from = std::max(epoch_ns(since), epoch_ns(now - std::chrono::seconds(5)));
  const long long to = epoch_ns(now + wait + std::chrono::milliseconds(500));
  for (;;) {
    if (const int fd = open_note(path, O_RDONLY); fd >= 0) {
      std::string text(512, '\0');
      const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
      ::close(fd);
      text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
      const auto nl = text.find('\n');
      char* end = nullptr;
      const long long ns = std::strtoll(text.c_str(), &end, 10);
      const std::size_t at = static_cast<std::size_t>(end - text.c_str());
      // "<ns> pid <pid>: <what>": said as "`<what>` (pid <pid>)".
      if (nl != std::string::npos && ns >= from && ns <= to && text.compare(at, 5, " pid ") == 0) {
        const std::string line = text.substr(at + 5, nl - at - 5);
        if (const auto colon = line.find(": "); colon != std::string::npos)
          return "`" + shown_text(line.substr(colon + 2)) + "` (pid " + shown_text(line.substr(0, colon)) + ")";
      }
    }
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void TableLock::check_free(const std::string& identity) {
  const std::string path = path_for(identity);
  std::string why;
  const int fd = open_lock_file(identity, path, why, false);
  if (fd < 0) return;
  const int err = flock_with_retries(fd, LOCK_SH);
  if (err == EWOULDBLOCK) {
    const InUseError e = in_use(identity, path, fd);
    ::close(fd);
    throw e;
  }
  ::close(fd);
}

}  // namespace rig::cli
