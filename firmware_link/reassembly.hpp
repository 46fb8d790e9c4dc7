// Stream reassembly: turns DUT_STREAM_X / DUT_STREAM_Y frames into samples in
// sequence order. The 24-bit wire counter is widened to 64 bits; a sample is
// complete when both halves arrived. Halves may arrive out of order within a
// small reorder window (a CAN controller's mailboxes can swap frames); a sample
// still incomplete when the stream has moved `window` samples past it is lost.
// Lost runs are counted and located (LinkStats::gap_list); the next delivered
// sample carries sample_status::kGapBefore. Duplicates and frames arriving after
// their sample was delivered or given up are dropped and counted.
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <span>

#include "firmware_link/protocol.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/types.hpp"

namespace rig::link {

class StreamReassembler {
 public:
  static constexpr std::size_t kMaxGapList = 1000;
  explicit StreamReassembler(uint32_t window = 8) : window_(window < 1 ? 1 : window) {}

  void push(const StreamHalf& h);
  // Moves up to out.size() completed samples, in order; returns how many.
  std::size_t pop(std::span<Sample> out);
  std::size_t ready() const { return ready_.size(); }
  // The stream ended (stop or silence): settle everything pending, so that
  // incomplete samples in the middle count as lost; trailing partial samples
  // are discarded (a stop cuts the stream at an arbitrary point).
  void flush();
  // Forget the position (a new stream starts); statistics are kept.
  void restart();

  const LinkStats& stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }
  // Widened sequence number of the next sample to be delivered (valid once started).
  uint64_t next_seq() const { return next_; }
  bool started() const { return started_; }
  // Statistics beyond LinkStats: halves that arrived without their partner.
  uint64_t orphan_halves() const { return orphans_; }

 private:
  struct Partial {
    bool has_x = false, has_y = false;
    float x = 0, y = 0;
    uint8_t status = 0;
  };
  uint64_t widen(uint32_t seq24) const;
  void advance_to(uint64_t limit);  // settles every sample below `limit`
  void emit(uint64_t seq, const Partial& p);
  void lose(uint64_t first, uint64_t count);
  void close_gap();

  uint32_t window_;
  bool started_ = false;
  uint64_t next_ = 0;     // next sample to deliver
  uint64_t highest_ = 0;  // highest widened seq seen
  std::map<uint64_t, Partial> pending_;
  std::deque<Sample> ready_;
  bool gap_open_ = false;
  uint64_t gap_start_ = 0, gap_len_ = 0;
  uint64_t orphans_ = 0;
  LinkStats stats_;
};

}  // namespace rig::link
