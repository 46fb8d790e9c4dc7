// A table client's record of the stops asked of it while one of its operations runs (both
// clients, rig-v1 map and CiA 402, keep one).
#pragma once
#include <atomic>
#include <cstdint>
#include <cstdio>
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
// (guarded_call). Only the operation's thread calls begin/end/since_begin; asked() is atomic.
class StopLatch {
 public:
  // A stop asked for (before its write, if any); a quick stop is counted as one first, so that a
  // stop seen since begin() is never named a halt when it was a quick stop.
  void asked(bool quick = false) noexcept {
    if (quick) quick_.fetch_add(1);
    asked_.fetch_add(1);
  }
  void begin(const std::string& doing) {
    doing_ = doing, at_begin_ = asked_.load(), quick_at_begin_ = quick_.load(), active_ = true;
  }
  void end() noexcept { active_ = false; }
  bool since_begin() const noexcept { return active_ && asked_.load() != at_begin_; }
  // What ended the operation, as its message names it: "halted by a stop request", or "… by a
  // quick stop request" if one was among them (read once since_begin() is true).
  std::string halted_by() const { return quick_.load() != quick_at_begin_ ? "halted by a quick stop request" : "halted by a stop request"; }
  // Writes one command word of the running operation (`write` sends it), never over a stop. An
  // abort (`cancel`) is said as one, as it was.
  template <class Write>
  void write_command(uint16_t word, const CancelToken& cancel, Write write) const {
    cancel.throw_if_requested();
    if (since_begin())
      throw HardwareError(doing_ + ": " + halted_by() + " (before command word " + word_hex(word) + " was written)");
    write();
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
  std::atomic<uint32_t> asked_{0}, quick_{0};
  uint32_t at_begin_ = 0, quick_at_begin_ = 0;
  bool active_ = false;
  std::string doing_;
};

}  // namespace rig::modbus::detail
