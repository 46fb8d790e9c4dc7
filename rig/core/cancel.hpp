// Cooperative cancellation for every blocking call at the seams.
// The executive owns one CancelSource; signals and the e-stop line trip it, and
// every wait (table move, sample read, clock sleep) polls its token and throws
// AbortedError, so no blocking call can stall the abort path.
#pragma once
#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "rig/core/errors.hpp"

namespace rig {

class CancelSource;

class CancelToken {
 public:
  CancelToken() = default;  // a token that is never cancelled
  bool requested() const noexcept { return state_ && state_->flag.load(std::memory_order_acquire); }
  std::string reason() const {
    if (!state_) return {};
    std::lock_guard lk(state_->mu);
    return state_->reason;
  }
  // Throws AbortedError when cancellation was requested.
  void throw_if_requested() const {
    if (requested()) throw AbortedError("aborted: " + reason());
  }

 private:
  friend class CancelSource;
  struct State {
    std::atomic<bool> flag{false};
    mutable std::mutex mu;
    std::string reason;
  };
  explicit CancelToken(std::shared_ptr<State> s) : state_(std::move(s)) {}
  std::shared_ptr<State> state_;
};

class CancelSource {
 public:
  CancelSource() : state_(std::make_shared<CancelToken::State>()) {}
  CancelToken token() const { return CancelToken(state_); }
  // First caller's reason wins. Not async-signal-safe: call from a normal thread.
  void request(const std::string& reason) {
    std::lock_guard lk(state_->mu);
    if (state_->flag.load()) return;
    state_->reason = reason;
    state_->flag.store(true, std::memory_order_release);
  }
  bool requested() const noexcept { return state_->flag.load(); }

 private:
  std::shared_ptr<CancelToken::State> state_;
};

}  // namespace rig
