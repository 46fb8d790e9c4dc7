// Descriptors a watcher thread polls, closed with their owner: the signal watcher's signalfd and,
// for it and the e-stop watcher, an eventfd another thread writes to wake the poll at once (both
// used to sleep out a polling slice before they saw a stop flag).
#pragma once
#include <sys/eventfd.h>
#include <unistd.h>

#include <cstdint>

namespace rig {

// Owns a descriptor (-1: none) and closes it.
class UniqueFd {
 public:
  explicit UniqueFd(int fd = -1) : fd_(fd) {}
  ~UniqueFd() {
    if (fd_ >= 0) ::close(fd_);
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// An eventfd to poll beside the descriptor a thread waits on. get() is -1 when the kernel gave
// none: the waits then end at their own timeouts.
class WakeFd {
 public:
  int get() const { return fd_.get(); }
  // Makes get() readable for good: the poll in progress and every later one return at once.
  void wake() const {
    if (fd_.get() < 0) return;
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &one, sizeof one);  // the counter is far from full
  }

 private:
  UniqueFd fd_{::eventfd(0, EFD_CLOEXEC)};
};

}  // namespace rig
