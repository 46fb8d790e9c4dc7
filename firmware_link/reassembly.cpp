#include "firmware_link/reassembly.hpp"

#include <algorithm>
#include <limits>

#include "rig/core/errors.hpp"

namespace rig::link {

StreamReassembler::StreamReassembler(uint32_t window, int counter_bits, bool needs_y, bool hold_start)
    : window_(window < 1 ? 1 : window),
      bits_(counter_bits),
      mask_(counter_bits >= 32 ? 0xFFFFFFFFu : (uint32_t{1} << counter_bits) - 1),
      needs_y_(needs_y),
      hold_start_(hold_start) {
  if (counter_bits < 2 || counter_bits > 32)
    throw ConfigError("stream counter of " + std::to_string(counter_bits) + " bits: the reassembly takes 2..32");
  // A counter that wraps within the reorder window could not tell late from new.
  if (!window_fits(window_, counter_bits))
    throw ConfigError("reorder window of " + std::to_string(window_) + " samples is more than half the " +
                      std::to_string(counter_bits) + "-bit counter's period");
}

int64_t StreamReassembler::widen_signed(uint32_t counter) const {
  // The widened value closest to the highest seen: deltas in [-2^(N-1), 2^(N-1)).
  const int64_t kHalf = int64_t{1} << (bits_ - 1), kFull = int64_t{1} << bits_;
  int64_t delta = static_cast<int64_t>((counter - static_cast<uint32_t>(highest_)) & mask_);
  if (delta >= kHalf) delta -= kFull;
  return static_cast<int64_t>(highest_) + delta;
}

uint64_t StreamReassembler::widen(uint32_t counter) const {
  const int64_t s = widen_signed(counter);
  return s < 0 ? 0 : static_cast<uint64_t>(s);  // before the stream's start: late by definition
}

void StreamReassembler::push_part(const StreamPart& h) {
  uint64_t s;
  if (!started_) {
    started_ = true;
    s = h.counter & mask_;
    next_ = highest_ = s;
  } else {
    const int64_t w = widen_signed(h.counter & mask_);
    if (w < 0) {  // before the stream's start (across a wrap): late, never sample 0 (a review)
      ++stats_.duplicates;
      return;
    }
    s = static_cast<uint64_t>(w);
  }
  if (s < next_ && !settled_ && hold_start_ && s + window_ > highest_) {
    next_ = s;  // the stream's first sample, logged late: nothing delivered yet, the start moves back
  } else if (s < next_) {  // its sample was already delivered or given up
    ++stats_.duplicates;
    return;
  }
  Partial& p = slot(s);
  bool& has = h.channel == Channel::X ? p.has_x : p.has_y;
  if (has) {
    ++stats_.duplicates;
    return;
  }
  has = true;
  (h.channel == Channel::X ? p.x : p.y) = h.value_g;
  if (h.status) p.status = *h.status;
  highest_ = std::max(highest_, s);
  // Deliver what is complete; give up on samples the stream has left `window_` behind.
  const uint64_t limit = highest_ + 1 >= window_ ? highest_ + 1 - window_ : 0;
  if (!settled_) {
    settled_ = !hold_start_ || limit > next_;
    if (!settled_) return;
    if (hold_start_) drop_leading_partials();
  }
  advance_to(std::max(limit, next_));
  while (!pending_.empty() && pending_.begin()->first == next_ && complete(pending_.begin()->second)) {
    emit(next_, pending_.begin()->second);
    release_first();
    ++next_;
  }
}

StreamReassembler::Partial& StreamReassembler::slot(uint64_t seq) {
  const auto it = pending_.lower_bound(seq);
  if (it != pending_.end() && it->first == seq) return it->second;
  if (spare_.empty()) return pending_.emplace_hint(it, seq, Partial{})->second;
  auto node = std::move(spare_.back());
  spare_.pop_back();
  node.key() = seq;
  node.mapped() = Partial{};
  return pending_.insert(it, std::move(node))->second;
}

void StreamReassembler::release_first() {
  constexpr std::size_t kMaxSpare = 16;  // a burst of reordering may leave more; the rest are freed
  auto node = pending_.extract(pending_.begin());
  if (spare_.size() < kMaxSpare) spare_.push_back(std::move(node));
}

void StreamReassembler::advance_to(uint64_t limit) {
  while (next_ < limit) {
    const uint64_t k = pending_.empty() ? limit : std::min(pending_.begin()->first, limit);
    if (k > next_) {  // nothing received for [next_, k): one lost run
      lose(next_, k - next_);
      next_ = k;
      continue;
    }
    const Partial p = pending_.begin()->second;
    release_first();
    if (complete(p)) {
      emit(next_, p);
    } else {
      ++orphans_;
      lose(next_, 1);
    }
    ++next_;
  }
}

void StreamReassembler::lose(uint64_t first, uint64_t count) {
  if (gap_open_ && gap_start_ + gap_len_ == first) {
    gap_len_ += count;
    return;
  }
  close_gap();
  gap_open_ = true;
  gap_start_ = first;
  gap_len_ = count;
}

void StreamReassembler::close_gap() {
  if (!gap_open_) return;
  ++stats_.gaps;
  stats_.lost += gap_len_;
  if (stats_.gap_list.size() < kMaxGapList) stats_.gap_list.emplace_back(gap_start_, gap_len_);
  gap_open_ = false;
}

void StreamReassembler::emit(uint64_t seq, const Partial& p) {
  Sample s;
  s.seq = static_cast<uint32_t>(seq);
  s.x_g = p.x;
  s.y_g = needs_y_ ? p.y : std::numeric_limits<float>::quiet_NaN();
  s.status = p.status;
  if (gap_open_) {
    close_gap();
    s.status |= sample_status::kGapBefore;
  }
  ready_.push_back(s);
}

std::size_t StreamReassembler::pop(std::span<Sample> out) {
  const std::size_t n = std::min(out.size(), ready_.size());
  std::copy_n(ready_.begin(), n, out.begin());
  ready_.erase(ready_.begin(), ready_.begin() + static_cast<std::ptrdiff_t>(n));
  stats_.received += n;  // LinkStats::received = samples delivered to the caller
  return n;
}

// A held start settles at its first complete sample: a log that begins between a sample's parts
// (or with a lone part logged late) holds the part of a sample it does not hold, which is no
// loss within the log (it counted as a gap at the start, a review). Dropped as orphans.
void StreamReassembler::drop_leading_partials() {
  const auto first = std::find_if(pending_.begin(), pending_.end(), [&](const auto& kv) { return complete(kv.second); });
  if (first == pending_.end()) return;
  const uint64_t k = first->first;
  while (pending_.begin()->first < k) {
    ++orphans_;
    release_first();
  }
  next_ = k;
}

std::size_t StreamReassembler::flush() {
  // Settle up to the last complete sample; partial samples after it are the
  // stream's cut-off tail and are dropped without counting a gap.
  uint64_t last_complete = 0;
  bool any = false;
  for (const auto& [k, p] : pending_)
    if (complete(p)) {
      last_complete = k;
      any = true;
    }
  if (!settled_ && hold_start_) drop_leading_partials();
  settled_ = true;
  if (any) advance_to(last_complete + 1);
  const std::size_t tail = pending_.size();
  orphans_ += tail;
  pending_.clear();
  return tail;
}

void StreamReassembler::restart() {
  pending_.clear();
  ready_.clear();
  gap_open_ = false;
  started_ = false;
  settled_ = false;
  next_ = highest_ = 0;
}

}  // namespace rig::link
