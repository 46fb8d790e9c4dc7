#include "app/table_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <string>

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

// The file's text: what the holder wrote ("pid 1234: rig run --out ..."), one line.
std::string read_holder(int fd) {
  std::string text(512, '\0');
  const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
  text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  if (const auto nl = text.find('\n'); nl != std::string::npos) text.resize(nl);
  return text.empty() ? std::string("another rig process") : shown_text(text);
}
}  // namespace

std::string TableLock::path_for(const std::string& identity) {
  std::string name = "rig-table-";
  for (const char c : identity) name += std::isalnum(static_cast<unsigned char>(c)) || c == '.' ? c : '_';
  return (fs::path(lock_folder()) / (name + ".lock")).string();
}

TableLock::TableLock(const std::string& identity, const std::string& holder) {
  const std::string path = path_for(identity);
  // Read-write to say who holds it; read-only (a file another account made) still locks. The lock
  // folder is shared (/run/lock, /tmp): a symlink planted there is not followed (root would
  // truncate its target), nor does a FIFO block the open; anything but a regular file is refused.
  constexpr int kSafe = O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK;
  int fd = ::open(path.c_str(), O_RDWR | O_CREAT | kSafe, 0644);
  if (fd < 0 && errno != ELOOP) fd = ::open(path.c_str(), O_RDONLY | kSafe);
  if (fd < 0 && errno == ELOOP)
    throw ConfigError("table " + identity + ": the lock file " + path + " is a symbolic link, which rig does not follow; "
                      "remove it (something other than rig put it there)");
  if (fd < 0) return;  // no lock folder this account may use: unlocked, as before
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw ConfigError("table " + identity + ": the lock file " + path +
                      " is not a regular file; remove it (something other than rig put it there)");
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string who = read_holder(fd);
    ::close(fd);
    if (err != EWOULDBLOCK) return;  // a file system without flock
    throw ConfigError("table " + identity + ": in use by " + who + " on this station (lock " + path +
                      "); wait for it to end. `rig table stop` and `rig table quick-stop` still reach the drive");
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

}  // namespace rig::cli
