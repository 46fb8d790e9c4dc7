// Stream reassembly: turns DUT_STREAM_X / DUT_STREAM_Y frames (or the parts a
// DBC-described stream's frames carry, firmware_link/dbc_stream.hpp) into samples in
// sequence order. The N-bit wire counter (24 bits in the rig protocol) is widened to 64
// bits; a sample is complete when both halves arrived (x alone for a stream without y). Halves may arrive out of order within a
// small reorder window (a CAN controller's mailboxes can swap frames); a sample
// still incomplete when the stream has moved `window` samples past it is lost.
// Lost runs are counted and located (LinkStats::gap_list); the next delivered
// sample carries sample_status::kGapBefore. Duplicates and frames arriving after
// their sample was delivered or given up are dropped and counted.
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include "firmware_link/protocol.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/types.hpp"

namespace rig::link {

// One channel's value of one sample, as the reassembly takes it.
struct StreamPart {
  Channel channel = Channel::X;
  uint32_t counter = 0;          // the wire counter (its low counter_bits bits are used)
  std::optional<uint8_t> status;  // stream_status bits, when this frame carries them
  float value_g = 0;
  // Decoded outside its signal's DBC range [min|max] (where the DBC gives one), or not finite:
  // a layout that does not fit the frames (byte order, sign, factor), for a log's import to say.
  bool implausible = false;
};

class StreamReassembler {
 public:
  static constexpr std::size_t kMaxGapList = 1000;
  // counter_bits: width of the wire counter (2..32; the rig protocol's is 24).
  // needs_y = false: a stream without y; a sample is complete with x, y_g is NaN.
  // hold_start: deliver nothing until the stream has moved `window` samples past its first
  // frame, so that a sample logged a few frames late at the very start (a log, not a live link,
  // has no reader waiting) takes its place instead of counting as a duplicate.
  explicit StreamReassembler(uint32_t window = 8, int counter_bits = 24, bool needs_y = true,
                             bool hold_start = false);

  // Whether a reorder window tells late from new with a counter of `counter_bits`: at most half
  // its period. The constructor's check; a hardware file's reader says it at the file's line.
  static bool window_fits(uint32_t window, int counter_bits) {
    return uint64_t{window} * 2 <= (uint64_t{1} << counter_bits);
  }

  void push_part(const StreamPart& p);
  // The rig protocol's frames (a distinct name keeps brace-initialised calls unambiguous).
  void push(const StreamHalf& h) { push_part(StreamPart{h.channel, h.seq24, h.status, h.value_g}); }
  // Moves up to out.size() completed samples, in order; returns how many.
  std::size_t pop(std::span<Sample> out);
  std::size_t ready() const { return ready_.size(); }
  // The stream ended (stop or silence): settle everything pending, so that
  // incomplete samples in the middle count as lost; trailing partial samples
  // are discarded (a stop cuts the stream at an arbitrary point). Returns how many.
  std::size_t flush();
  // Forget the position (a new stream starts); statistics are kept.
  void restart();

  const LinkStats& stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }
  // Widened sequence number of the next sample to be delivered (valid once started).
  uint64_t next_seq() const { return next_; }
  bool started() const { return started_; }
  // Statistics beyond LinkStats: halves that arrived without their partner.
  uint64_t orphan_halves() const { return orphans_; }
  // Where a frame's counter would land (widened next to the highest seen), before pushing it:
  // more than `window` behind next_seq() is no reordering a controller does (a counter that
  // went back: the DUT restarted), which a caller that can stop (a log's import) names.
  uint64_t widened(uint32_t counter) const { return started_ ? widen(counter & mask_) : counter & mask_; }
  uint32_t window() const { return window_; }
  uint32_t counter_mask() const { return mask_; }  // the wire counter's bits
  uint64_t highest_seq() const { return highest_; }  // the highest widened seq seen
  int counter_bits() const { return bits_; }

 private:
  struct Partial {
    bool has_x = false, has_y = false;
    float x = 0, y = 0;
    uint8_t status = 0;
  };
  uint64_t widen(uint32_t counter) const;
  int64_t widen_signed(uint32_t counter) const;  // below 0: before the stream's start
  void drop_leading_partials();
  bool complete(const Partial& p) const { return p.has_x && (p.has_y || !needs_y_); }
  void advance_to(uint64_t limit);  // settles every sample below `limit`
  void emit(uint64_t seq, const Partial& p);
  void lose(uint64_t first, uint64_t count);
  void close_gap();
  Partial& slot(uint64_t seq);  // pending_[seq], reusing a spare node
  void release_first();         // erases pending_.begin(), keeping its node as a spare

  uint32_t window_;
  int bits_;
  uint32_t mask_;
  bool needs_y_;
  bool hold_start_;
  bool settled_ = false;  // hold_start: the start may still move back
  bool started_ = false;
  uint64_t next_ = 0;     // next sample to deliver
  uint64_t highest_ = 0;  // highest widened seq seen
  std::map<uint64_t, Partial> pending_;
  // Nodes of settled samples, reused for the next ones: a stream in order keeps one or two
  // samples pending, so after the first few it allocates nothing per sample.
  std::vector<std::map<uint64_t, Partial>::node_type> spare_;
  std::deque<Sample> ready_;
  bool gap_open_ = false;
  uint64_t gap_start_ = 0, gap_len_ = 0;
  uint64_t orphans_ = 0;
  LinkStats stats_;
};

}  // namespace rig::link
