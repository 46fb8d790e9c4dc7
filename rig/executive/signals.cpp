#include "rig/executive/signals.hpp"

#include <pthread.h>
#include <signal.h>

#include <ctime>
#include <string>

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
}  // namespace

SignalWatcher::SignalWatcher(CancelSource& source) : source_(source) {
  const sigset_t s = abort_signals();
  pthread_sigmask(SIG_BLOCK, &s, nullptr);
  thread_ = std::thread([this, s] {
    const timespec slice{0, 100'000'000};
    while (!stop_.load()) {
      const int sig = sigtimedwait(&s, nullptr, &slice);
      if (sig > 0) source_.request(std::string(sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "SIGHUP") +
                                   " received");
    }
  });
}

SignalWatcher::~SignalWatcher() {
  stop_ = true;
  thread_.join();
  const sigset_t s = abort_signals();
  pthread_sigmask(SIG_UNBLOCK, &s, nullptr);
}

}  // namespace rig
