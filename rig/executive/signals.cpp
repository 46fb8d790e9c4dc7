#include "rig/executive/signals.hpp"

#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <system_error>

namespace rig {

namespace {
// SIGHUP is taken unless the process started with it ignored: `nohup rig ...` asks that a
// closed terminal not end the run (or move), and the watcher would otherwise override that.
// SIGQUIT (Ctrl-\) is taken as SIGINT is: its default action ended the process with no halt, and
// the table drove on to its target (a technician's re-test). Like SIGINT it is taken even when the
// process started with it ignored: a shell without job control ignores both in its background
// jobs, which is no request of the user's (a review: `kill -QUIT` left `rig plant serve &` running).
sigset_t abort_signals() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGINT);
  sigaddset(&s, SIGTERM);
  sigaddset(&s, SIGQUIT);
  struct sigaction was {};
  if (sigaction(SIGHUP, nullptr, &was) != 0 || was.sa_handler != SIG_IGN) sigaddset(&s, SIGHUP);
  return s;
}

const char* signal_name(uint32_t sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGQUIT ? "SIGQUIT" : "SIGHUP";
}
}  // namespace

// The signalfd is non-blocking: a read finds the signal or nothing (with two watchers alive, both polls see one
// signal and only one read takes it).
SignalWatcher::SignalWatcher(CancelSource& source)
    : source_(source), signal_fd_([] {
        const sigset_t s = abort_signals();
        return signalfd(-1, &s, SFD_CLOEXEC | SFD_NONBLOCK);
      }()) {
  if (signal_fd_.get() < 0 || wake_.get() < 0) throw std::system_error(errno, std::generic_category(), "signal watcher");
  const sigset_t s = abort_signals();
  pthread_sigmask(SIG_BLOCK, &s, nullptr);
  // The thread sleeps in poll until a signal or the destructor's wake: it used to wake every
  // 100 ms to look at a stop flag, and every command's exit waited out the slice (a `paper`
  // run's last 40-100 ms).
  try {
    thread_ = std::thread([this] {
      pollfd fds[2] = {{signal_fd_.get(), POLLIN, 0}, {wake_.get(), POLLIN, 0}};
      for (;;) {
        if (poll(fds, 2, -1) < 0 && errno != EINTR) return;
        // Every signal pending is taken before the wake is looked at: one left pending would be
        // delivered when the destructor unblocks the signals, and its default action would end a
        // process that has finished (a code review: exit 130 after "outcome PASS").
        take_pending();
        if (fds[1].revents != 0) return;
      }
    });
  } catch (...) {  // the descriptors close with their members
    pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
    throw;
  }
}

void SignalWatcher::take_pending() {
  for (signalfd_siginfo info{}; read(signal_fd_.get(), &info, sizeof info) == sizeof info;)
    source_.request(std::string(signal_name(info.ssi_signo)) + " received");
}

SignalWatcher::~SignalWatcher() {
  wake_.wake();
  thread_.join();
  take_pending();  // one that came after the thread's last look
  const sigset_t s = abort_signals();
  pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
}

}  // namespace rig
