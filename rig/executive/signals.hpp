// SIGINT/SIGTERM -> cancellation. The signals are blocked in every thread and
// taken by one watcher thread with sigtimedwait, so the handler side is plain
// code (no async-signal-safety limits) and blocking calls see the cancel token.
#pragma once
#include <atomic>
#include <thread>

#include "rig/core/cancel.hpp"

namespace rig {

class SignalWatcher {
 public:
  // Construct before any other thread starts (threads inherit the signal mask).
  explicit SignalWatcher(CancelSource& source);
  ~SignalWatcher();
  SignalWatcher(const SignalWatcher&) = delete;
  SignalWatcher& operator=(const SignalWatcher&) = delete;

 private:
  CancelSource& source_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace rig
