// A table client's record of the stops asked of it while one of its operations runs (both
// clients, rig-v1 map and CiA 402, keep one).
#pragma once
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

#include "rig/core/cancel.hpp"
#include "rig/core/errors.hpp"

namespace rig::modbus::detail {

// The stops (halt, quick stop) asked of a client while one of its operations (a move, a homing
// run) runs, sent or not (a CiA 402 drive with its power stage off gets none). The clients let
// stop() be called from another thread while an operation runs (the rig's own abort paths do
// not: they cancel the operation, whose thread then sends the stop after its last word), and a
// command word the operation writes after such a stop would write over it (a whole controlword:
// halt cleared, the move started). So the operation writes no command word once a stop was asked
// for, and one written as a stop was asked for ends it too: the stop may have reached the drive
// just before that word, which then cleared it, so the operation's fault path sends it again
// (guarded_call). Only the operation's thread calls begin/end/since_begin; Asking counts from any.
class StopLatch {
 public:
  // Counts one stop (a quick stop if `quick`) from the top of stop()/quick_stop(), before its
  // write if any, to its return (sent, refused or failed). A stop still under way when an
  // operation begins counts for it too: its write may land after the operation's first command
  // word, which would then clear it, or be read back as another master's (an outside review).
  // It also holds the client's stop sending for that stop: stops go out one at a time (a halt
  // decided beside a quick stop under way would weaken it, a code review).
  class Asking {
   public:
    Asking(StopLatch& l, bool quick) : l_(l), one_(quick ? kOne | kOneQuick : kOne) {
      l_.asked_.fetch_add(one_);
      sending_ = std::unique_lock(l_.sending_);
    }
    ~Asking() {
      sending_.unlock();
      l_.done_.fetch_add(one_);
    }
    Asking(const Asking&) = delete;
    Asking& operator=(const Asking&) = delete;

   private:
    StopLatch& l_;
    uint64_t one_;
    std::unique_lock<std::mutex> sending_;
  };
  // A quick stop of this client's stands from its delivery (quick_stop_sent(true)) to the client's
  // next command word (write_command): a halt after it must keep it (a HALT edge re-plans the
  // rest on the profile ramp, a CiA 402 0x010F in Quick stop active is transition 16, back to
  // Operation enabled: an outside review and a code review).
  void quick_stop_sent(bool delivered) noexcept { quick_stands_ = delivered; }
  bool quick_stop_stands() const noexcept { return quick_stands_; }
  void begin(const std::string& doing) { doing_ = doing, at_begin_ = done_.load(), active_ = true; }
  void end() noexcept { active_ = false; }
  // Stops asked since the operation began, or under way when it did.
  bool since_begin() const noexcept { return active_ && stops(asked_.load()) != stops(at_begin_); }
  bool quick_since_begin() const noexcept { return active_ && quicks(asked_.load()) != quicks(at_begin_); }
  // What ended the operation, as its message names it: "halted by a stop request", or "… by a
  // quick stop request" if one was among them. Both counts move in one atomic step, so a quick
  // stop is never read as a halt.
  std::string halted_by() const { return quick_since_begin() ? "halted by a quick stop request" : "halted by a stop request"; }
  // The stop a failed operation sends again (guarded_call): the kind asked of it, a quick stop if
  // one was (a halt after it slowed the stop to the profile ramp: 22.8° of travel where the quick
  // stop took 6.6°, an outside review). Returns the name said of it.
  template <class QuickStop, class Halt>
  const char* send_again(QuickStop quick_stop, Halt halt) const {
    if (quick_since_begin())
      quick_stop();
    else
      halt();  // keeps a quick stop asked meanwhile (quick_stop_stands)
    return quick_since_begin() ? "quick stop" : "halt";
  }
  // Writes one command word of the running operation (`write` sends it), never over a stop. An
  // abort (`cancel`) is said as one, as it was.
  template <class Write>
  void write_command(uint16_t word, const CancelToken& cancel, Write write) {
    cancel.throw_if_requested();
    if (since_begin()) throw HardwareError(doing_ + ": " + halted_by() + " (before command word " + word_hex(word) + " was written)");
    write();
    quick_stands_ = false;
    cancel.throw_if_requested();
    if (since_begin())
      throw HardwareError(doing_ + ": " + halted_by() + " that came as command word " + word_hex(word) +
                          " was written (which may have cleared it: the stop is sent again)");
  }
  // While it lives, the operation `doing` runs: from the top of a client's home() or move_to(),
  // so a stop asked during a move's first read counts too.
  struct Scope {
    StopLatch& l;
    Scope(StopLatch& latch, const std::string& doing) : l(latch) { l.begin(doing); }
    ~Scope() { l.end(); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
  };

 private:
  static std::string word_hex(uint16_t w) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%04X", w);
    return b;
  }
  // Stops in the low 32 bits, quick stops among them in the high 32: one fetch_add counts both.
  static constexpr uint64_t kOne = 1, kOneQuick = uint64_t{1} << 32;
  static uint32_t stops(uint64_t v) noexcept { return static_cast<uint32_t>(v); }
  static uint32_t quicks(uint64_t v) noexcept { return static_cast<uint32_t>(v >> 32); }
  std::atomic<uint64_t> asked_{0}, done_{0};  // counted at a stop's top and at its return
  uint64_t at_begin_ = 0;                     // done_ when the operation began
  std::mutex sending_;                        // held by each Asking
  std::atomic<bool> quick_stands_{false};
  bool active_ = false;
  std::string doing_;
};

}  // namespace rig::modbus::detail
