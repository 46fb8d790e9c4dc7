#include "rig/executive/signals.hpp"

#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <system_error>

namespace rig {

namespace {
// SIGHUP is taken unless the process started with it ignored: `nohup rig ...` asks that a
// closed terminal not end the run (or move), and the watcher would otherwise override that.
sigset_t abort_signals() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGINT);
  sigaddset(&s, SIGTERM);
  struct sigaction hup {};
  if (sigaction(SIGHUP, nullptr, &hup) != 0 || hup.sa_handler != SIG_IGN) sigaddset(&s, SIGHUP);
  return s;
}

const char* signal_name(uint32_t sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "SIGHUP";
}
}  // namespace

SignalWatcher::SignalWatcher(CancelSource& source) : source_(source) {
  const sigset_t s = abort_signals();
  pthread_sigmask(SIG_BLOCK, &s, nullptr);
  // Non-blocking: a read finds the signal or nothing (with two watchers alive, both polls see one
  // signal and only one read takes it).
  signal_fd_ = signalfd(-1, &s, SFD_CLOEXEC | SFD_NONBLOCK);
  wake_fd_ = eventfd(0, EFD_CLOEXEC);
  if (signal_fd_ < 0 || wake_fd_ < 0) {
    const int err = errno;
    if (signal_fd_ >= 0) close(signal_fd_);
    if (wake_fd_ >= 0) close(wake_fd_);
    pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
    throw std::system_error(err, std::generic_category(), "signal watcher");
  }
  // The thread sleeps in poll until a signal or the destructor's wake: it used to wake every
  // 100 ms to look at a stop flag, and every command's exit waited out the slice (a `paper`
  // run's last 40-100 ms).
  try {
    thread_ = std::thread([this] {
      pollfd fds[2] = {{signal_fd_, POLLIN, 0}, {wake_fd_, POLLIN, 0}};
      for (;;) {
        if (poll(fds, 2, -1) < 0 && errno != EINTR) return;
        // Every signal pending is taken before the wake is looked at: one left pending would be
        // delivered when the destructor unblocks the signals, and its default action would end a
        // process that has finished (a code review: exit 130 after "outcome PASS").
        take_pending();
        if (fds[1].revents != 0) return;
      }
    });
  } catch (...) {
    close(signal_fd_);
    close(wake_fd_);
    pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
    throw;
  }
}

void SignalWatcher::take_pending() {
  for (signalfd_siginfo info{}; read(signal_fd_, &info, sizeof info) == sizeof info;)
    source_.request(std::string(signal_name(info.ssi_signo)) + " received");
}

SignalWatcher::~SignalWatcher() {
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);  // cannot fail: the counter is far from full
  thread_.join();
  take_pending();  // one that came after the thread's last look
  close(signal_fd_);
  close(wake_fd_);
  const sigset_t s = abort_signals();
  pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
}

}  // namespace rig
