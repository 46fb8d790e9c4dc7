#include "app/table_lock.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

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
int open_lock_file(const std::string& identity, const std::string& path, std::string& why, bool create = true) {
  constexpr int kSafe = O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK;
  int fd = ::open(path.c_str(), O_RDWR | (create ? O_CREAT : 0) | kSafe, 0644);
  // Read-only still locks (a file another account made); it cannot say who holds it.
  if (fd < 0 && errno == EACCES) fd = ::open(path.c_str(), O_RDONLY | kSafe);
  if (fd < 0) {
    const int err = errno;
    struct stat st {};
    if (err == ELOOP) throw planted(identity, path, "a symbolic link");
    if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) throw planted(identity, path, "not a regular file");
    if (!create && err == ENOENT) return -1;
    why = "cannot open the lock file " + path + ": " + std::strerror(err);
    return -1;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink != 1) {
    const bool linked = S_ISREG(st.st_mode) && st.st_nlink != 1;
    ::close(fd);
    throw planted(identity, path, linked ? "a hard link to another file" : "not a regular file");
  }
  return fd;
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
