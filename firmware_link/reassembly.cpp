#include "firmware_link/reassembly.hpp"

#include <algorithm>

namespace rig::link {

uint64_t StreamReassembler::widen(uint32_t seq24) const {
  // The widened value closest to the highest seen: deltas in [-2^23, 2^23).
  constexpr int64_t kHalf = int64_t{1} << 23, kFull = int64_t{1} << 24;
  int64_t delta = static_cast<int64_t>((seq24 - static_cast<uint32_t>(highest_)) & kSeqMask);
  if (delta >= kHalf) delta -= kFull;
  const int64_t s = static_cast<int64_t>(highest_) + delta;
  return s < 0 ? 0 : static_cast<uint64_t>(s);  // before the stream's start: late by definition
}

void StreamReassembler::push(const StreamHalf& h) {
  uint64_t s;
  if (!started_) {
    started_ = true;
    s = h.seq24 & kSeqMask;
    next_ = highest_ = s;
  } else {
    s = widen(h.seq24 & kSeqMask);
  }
  if (s < next_) {  // its sample was already delivered or given up
    ++stats_.duplicates;
    return;
  }
  Partial& p = pending_[s];
  bool& has = h.channel == Channel::X ? p.has_x : p.has_y;
  if (has) {
    ++stats_.duplicates;
    return;
  }
  has = true;
  (h.channel == Channel::X ? p.x : p.y) = h.value_g;
  p.status = h.status;
  highest_ = std::max(highest_, s);
  // Deliver what is complete; give up on samples the stream has left `window_` behind.
  const uint64_t limit = highest_ + 1 >= window_ ? highest_ + 1 - window_ : 0;
  advance_to(std::max(limit, next_));
  while (!pending_.empty() && pending_.begin()->first == next_ && pending_.begin()->second.has_x &&
         pending_.begin()->second.has_y) {
    emit(next_, pending_.begin()->second);
    pending_.erase(pending_.begin());
    ++next_;
  }
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
    pending_.erase(pending_.begin());
    if (p.has_x && p.has_y) {
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
  s.y_g = p.y;
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

void StreamReassembler::flush() {
  // Settle up to the last complete sample; partial samples after it are the
  // stream's cut-off tail and are dropped without counting a gap.
  uint64_t last_complete = 0;
  bool any = false;
  for (const auto& [k, p] : pending_)
    if (p.has_x && p.has_y) {
      last_complete = k;
      any = true;
    }
  if (any) advance_to(last_complete + 1);
  orphans_ += pending_.size();
  pending_.clear();
}

void StreamReassembler::restart() {
  pending_.clear();
  ready_.clear();
  gap_open_ = false;
  started_ = false;
  next_ = highest_ = 0;
}

}  // namespace rig::link
