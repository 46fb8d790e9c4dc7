// A run folder held by one `rig run` at a time: an exclusive flock(2) on the folder itself,
// held for the process's life (the kernel drops it when the process ends, however it ends).
// No lock file is left behind, so a sealed folder still lists only what the run wrote.
#pragma once
#include <string>

namespace rig::cli {

// flock(2) of `op` (LOCK_EX or LOCK_SH) on `fd` without waiting, tried up to 10 times 20 ms
// apart: a dry run's check holds a shared lock for an instant, which is not "in use". 0 when
// taken, else the errno of the last try (EWOULDBLOCK: another process holds it).
int flock_with_retries(int fd, int op);

class FolderLock {
 public:
  // Takes the lock on the existing folder `dir` without waiting. Throws ConfigError naming the
  // folder when another process holds it; `what` says what the folder is for ("--out X", ...).
  // Where the filesystem has no flock (some network mounts) the run goes on unlocked: the
  // folder checks that run before it still apply, as they did before there was a lock.
  // `must_lock` false (a command that only reads the folder and writes a file into it): a folder
  // that cannot be opened to lock (no read permission) is left unlocked rather than refused.
  FolderLock(const std::string& dir, const std::string& what, bool must_lock = true);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  bool held() const { return fd_ >= 0; }

  // For --dry-run, which takes nothing: throws the same ConfigError when another process holds
  // the lock of `dir` now (nothing when `dir` does not exist).
  static void check_free(const std::string& dir, const std::string& what);
  // Whether another process holds the lock of `dir` now (false when `dir` does not exist or its
  // filesystem has no flock).
  static bool held_elsewhere(const std::string& dir);

 private:
  int fd_ = -1;
};

}  // namespace rig::cli
