// SIGINT/SIGTERM/SIGHUP/SIGQUIT -> cancellation. The signals are blocked in every thread and
// taken by one watcher thread through a signalfd, so the handler side is plain
// code (no async-signal-safety limits) and blocking calls see the cancel token.
#pragma once
#include <thread>

#include "rig/core/cancel.hpp"
#include "rig/core/wake_fd.hpp"

namespace rig {

class SignalWatcher {
 public:
  // Construct before any other thread starts (threads inherit the signal mask). Throws
  // std::system_error when the kernel gives no signalfd or eventfd.
  explicit SignalWatcher(CancelSource& source);
  ~SignalWatcher();
  SignalWatcher(const SignalWatcher&) = delete;
  SignalWatcher& operator=(const SignalWatcher&) = delete;

 private:
  void take_pending();  // reads every signal queued on signal_fd_ into the cancel source

  CancelSource& source_;
  UniqueFd signal_fd_;  // the abort signals, read by the thread
  WakeFd wake_;         // the destructor wakes it: the thread leaves at once
  std::thread thread_;
};

}  // namespace rig
