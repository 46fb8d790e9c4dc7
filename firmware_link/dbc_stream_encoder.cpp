// DbcStreamEncoder: the inverse of DbcStreamDecoder::decode (firmware_link/dbc_stream.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "firmware_link/dbc_stream.hpp"
#include "rig/core/errors.hpp"

namespace rig::link {

namespace {

constexpr uint8_t kFlagBits[3] = {stream_status::kFilterOn, stream_status::kSaturated, stream_status::kLoopFault};

// The raw value of `physical`, held inside an integer signal's range (no wrap-around: a DUT
// at its range end reports the end value).
uint64_t raw_clamped(const DbcSignal& s, double physical) {
  if (s.value_type != 0) return dbc_raw_of(s, physical);
  const double lo_raw = s.is_signed ? -std::ldexp(1.0, s.length - 1) : 0.0;
  const double hi_raw = s.is_signed ? std::ldexp(1.0, s.length - 1) - 1 : std::ldexp(1.0, s.length) - 1;
  double r = std::nearbyint((physical - s.offset) / s.factor);
  if (!std::isfinite(r)) r = r > 0 ? hi_raw : lo_raw;
  r = std::clamp(r, lo_raw, hi_raw);
  return dbc_raw_of(s, r * s.factor + s.offset);
}

void put(std::span<uint8_t> p, const DbcSignal& s, uint64_t raw) { dbc_insert_raw(p, s.start, s.length, s.big_endian, raw); }

}  // namespace

DbcStreamEncoder::DbcStreamEncoder(std::shared_ptr<const DbcStreamDecoder> layout) : layout_(std::move(layout)) {
  for (const auto& entry : layout_->by_frame_) {
    const auto& r = entry.second;  // not a structured binding: clang 14 (the fuzz build) cannot capture one
    // The multiplexer values the roles live under: one frame per value, each carrying the roles
    // of its page (x on page 0 and y on page 1 is two frames per sample, as such a DUT sends
    // them; the decoder joins the parts by their counter). A multiplexed counter selects a page
    // of its own, where every role must then live (the decoder needs a counter on each page).
    std::vector<int> pages;
    auto need = [&](const DbcSignal* s) {
      if (s && s->mux_value && std::find(pages.begin(), pages.end(), *s->mux_value) == pages.end())
        pages.push_back(*s->mux_value);
    };
    for (const auto& sl : r.samples) {
      need(sl.x);
      need(sl.y);
      need(sl.status);
      for (const DbcSignal* f : sl.flag) need(f);
    }
    if (r.counter->mux_value) {
      for (int v : pages)
        if (v != *r.counter->mux_value)
          throw ConfigError("stream message " + r.msg->name + " cannot be encoded: its counter is sent only under "
                            "multiplexer value " + std::to_string(*r.counter->mux_value) + ", a role under " +
                            std::to_string(v));
      pages = {*r.counter->mux_value};
    }
    std::sort(pages.begin(), pages.end());
    pages_[entry.first] = pages;
    fd_ = fd_ || r.msg->dlc > 8;
  }
}

void DbcStreamEncoder::encode(uint32_t counter, std::span<const StreamSample> samples, std::vector<CanFdFrame>& out) const {
  const DbcStreamDecoder& d = *layout_;
  if (samples.size() != static_cast<std::size_t>(d.spec_.samples_per_frame))
    throw std::invalid_argument("DbcStreamEncoder::encode: " + std::to_string(samples.size()) + " samples, the layout has " +
                                std::to_string(d.spec_.samples_per_frame) + " per frame");
  uint8_t all = 0;  // shared status/flag signals carry every sample's flags
  for (const StreamSample& s : samples) all |= s.status;
  for (const auto& entry : d.by_frame_) {
    const auto& r = entry.second;  // not a structured binding: clang 14 (the fuzz build) cannot capture one
    const std::vector<int>& pages = pages_.at(entry.first);
    for (std::size_t k = 0; k < std::max<std::size_t>(pages.size(), 1); ++k)
      encode_page(r, pages.empty() ? std::nullopt : std::optional<int>(pages[k]), counter, samples, all, out);
  }
}

void DbcStreamEncoder::encode_page(const DbcStreamDecoder::Roles& r, std::optional<int> page, uint32_t counter,
                                   std::span<const StreamSample> samples, uint8_t all, std::vector<CanFdFrame>& out) const {
  const DbcStreamDecoder& d = *layout_;
  const int* bits[3] = {&d.spec_.filter_on_bit, &d.spec_.saturated_bit, &d.spec_.loop_fault_bit};
  const DbcMessage& m = *r.msg;
  CanFdFrame f;
  f.id = m.id;
  f.extended = m.extended;
  f.fd = m.dlc > 8;
  f.len = static_cast<uint8_t>(canfd_round_up(m.dlc));
  const std::span<uint8_t> p(f.data.data(), f.len);
  // A role signal is in this frame when it is not multiplexed or lives under this page.
  const auto here = [&](const DbcSignal* s) { return s && (!s->mux_value || s->mux_value == page); };
  if (page)
    for (const auto& s : m.signals)
      if (s.multiplexor) put(p, s, static_cast<uint64_t>(*page));
  put(p, *r.counter, counter);  // dbc_insert_raw keeps its low bits
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const auto& sl = r.samples[i];
    const StreamSample& smp = samples[i];
    if (here(sl.x)) put(p, *sl.x, raw_clamped(*sl.x, smp.x_g / d.x_scale_));
    if (here(sl.y)) put(p, *sl.y, raw_clamped(*sl.y, smp.y_g / d.y_scale_));
    // A signal without an index is the same signal for every sample: it carries them all.
    const auto shared = [&](const DbcSignal* s) { return r.samples.size() > 1 && r.samples[0].status == s && r.samples[1].status == s; };
    if (here(sl.status)) {
      const uint8_t st = shared(sl.status) ? all : smp.status;
      uint64_t raw = 0;
      for (int b = 0; b < 3; ++b)
        if (*bits[b] >= 0 && (st & kFlagBits[b])) raw |= uint64_t{1} << *bits[b];
      put(p, *sl.status, raw);
    }
    for (int b = 0; b < 3; ++b)
      if (here(sl.flag[b])) {
        const bool is_shared = r.samples.size() > 1 && r.samples[0].flag[b] == sl.flag[b] && r.samples[1].flag[b] == sl.flag[b];
        const uint8_t st = is_shared ? all : smp.status;
        put(p, *sl.flag[b], raw_clamped(*sl.flag[b], (st & kFlagBits[b]) ? 1.0 : 0.0));
      }
  }
  out.push_back(f);
}

}  // namespace rig::link
