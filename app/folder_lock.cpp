#include "app/folder_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "rig/core/errors.hpp"

namespace rig::cli {

namespace {
int open_dir(const std::string& dir) { return ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); }
// The advice fits what the folder was for: only a new run can choose another folder (a resume
// was told to "choose another --out", a review).
ConfigError in_use(const std::string& what) {
  return ConfigError(what + ": another rig run is using this folder now (it holds the folder's lock; a run or resume, "
                            "or a report or history record being written); wait for it to end" +
                     (what.rfind("--out", 0) == 0 ? " or choose another --out" : ""));
}
}  // namespace

int flock_with_retries(int fd, int op) {
  int err = 0;
  for (int attempt = 0; attempt < 10; ++attempt) {
    if (::flock(fd, op | LOCK_NB) == 0) return 0;
    err = errno;
    if (err != EWOULDBLOCK) return err;
    ::usleep(20000);
  }
  return err;
}

FolderLock::FolderLock(const std::string& dir, const std::string& what, bool must_lock) {
  const int fd = open_dir(dir);
  if (fd < 0 && !must_lock) return;  // a reader's lock, on a folder it may read without listing
  if (fd < 0) throw ConfigError(what + ": cannot open the run folder to lock it: " + std::strerror(errno));
  const int err = flock_with_retries(fd, LOCK_EX);
  if (err == 0) {
    fd_ = fd;
    return;
  }
  ::close(fd);
  if (err == EWOULDBLOCK) throw in_use(what);
  // ENOLCK/EBADF/EOPNOTSUPP: a filesystem without flock on directories; nothing to hold.
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

bool FolderLock::held_elsewhere(const std::string& dir) {
  const int fd = open_dir(dir);
  if (fd < 0) return false;
  // A shared lock is refused only while someone holds the exclusive one; released at close.
  const bool busy = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  return busy;
}

void FolderLock::check_free(const std::string& dir, const std::string& what) {
  if (held_elsewhere(dir)) throw in_use(what);
}

}  // namespace rig::cli
