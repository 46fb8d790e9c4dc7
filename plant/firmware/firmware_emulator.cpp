#include "plant/firmware/firmware_emulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>

#include "rig/core/errors.hpp"

namespace rig::plant {

using link::Op;
using link::Result;

namespace {
constexpr double kRangeG = 10.0;        // docs/method.md: range +-10 g
// A loop test's burst leaves at about the pace of a 1 Mbit/s bus: 8-byte frames of at most 135
// bits (docs/can-protocol.md "Bus load") are 7.4 per ms.
constexpr int kBurstFramesPerTick = 7;

}  // namespace

FirmwareEmulator::FirmwareEmulator(DutSource& source, link::CanTransport& bus, FirmwareOptions opts)
    : src_(source), bus_(bus), opts_(opts), counter_(opts.first_seq) {
  // The firmware only listens to the rig's commands.
  const link::CanFilter f[] = {{link::can_id::kCommand, 0x7FF}};
  bus_.set_filters(f);
  streaming_ = !opts_.commands;  // without commands it streams from power-on
}

FirmwareEmulator::~FirmwareEmulator() { stop(); }

void FirmwareEmulator::set_faults(FirmwareFaults f) {
  std::lock_guard lk(mu_);
  faults_ = std::move(f);
  stats_.drop_hits.resize(faults_.drop_samples.size());
}

FirmwareStats FirmwareEmulator::stats() const {
  std::lock_guard lk(mu_);
  return stats_;
}

uint64_t FirmwareEmulator::sample_counter() const {
  std::lock_guard lk(mu_);
  return counter_;
}

bool FirmwareEmulator::silent() const { return faults_.silent_from && counter_ >= *faults_.silent_from; }

void FirmwareEmulator::send(const link::CanFrame& f) {
  if (silent()) return;
  tx_.push_back(f);
}

// A tick's frames leave together at its end, in the order they were sent: a real MCU's CAN
// controller also queues them within the period, and the in-process bus takes its locks
// once per batch instead of once per frame (issue 17).
void FirmwareEmulator::flush_sends() {
  std::vector<link::CanFrame> frames;
  frames.swap(tx_);  // a send that throws leaves no frames behind for the next tick
  bus_.send_batch(frames);
  stats_.frames_sent += frames.size();
  frames.clear();
  tx_.swap(frames);  // keep the capacity
}

void FirmwareEmulator::step(double dt_s) {
  if (!(dt_s > 0)) return;
  time_acc_ += dt_s * 1e9;
  if (time_acc_ < static_cast<double>(kFirmwareTickNs) - 0.5) return;
  // One lock for the slice's ticks (the world steps about 10 ms at a time), not one per tick,
  // and one batch of frames on the bus: in lockstep the simulated time stands still during the
  // slice, so its ticks' frames carry one timestamp whether they leave tick by tick or together,
  // and the rig reads none of them before the slice ends.
  std::lock_guard lk(mu_);
  try {
    while (time_acc_ >= static_cast<double>(kFirmwareTickNs) - 0.5) {  // tolerate rounding of many small dt
      tick();
      time_acc_ -= static_cast<double>(kFirmwareTickNs);
    }
  } catch (...) {
    flush_sends();  // the frames of the ticks before the fault leave, as they did tick by tick
    throw;
  }
  flush_sends();
}

void FirmwareEmulator::tick() {
  handle_commands();
  // The DUT's loop runs whether or not the rig listens: the physics and the
  // sample counter advance every output period.
  float x = 0, y = 0;
  if (loop_ && loop_->quiet_ticks == 0) {
    loop_test_period();
  } else {
    if (loop_) --loop_->quiet_ticks;
    src_.next(x, y);
  }
  for (int i = 0; i < kBurstFramesPerTick && !burst_.empty(); ++i) {
    send(burst_.front());
    burst_.pop_front();
  }
  const uint64_t seq = counter_++;
  if (streaming_) {
    ++stats_.samples;
    uint8_t status = src_.filter_enabled() ? link::stream_status::kFilterOn : 0;
    if (std::abs(x) >= kRangeG) status |= link::stream_status::kSaturated;
    send_sample(seq, x, y, status);
  }
  ++ticks_;
  const auto hb_every = static_cast<uint64_t>(std::max(1.0, std::round(1000.0 / opts_.heartbeat_hz)));
  if (ticks_ % hb_every == 0) {
    link::Heartbeat h;
    h.state = (streaming_ ? link::hb_state::kStreaming : 0) | (src_.filter_enabled() ? link::hb_state::kFilterOn : 0);
    h.counter = hb_counter_++;
    h.temperature_c = src_.temperature_c();
    h.last_seq = static_cast<uint32_t>(seq);
    send(link::encode(h));
  }
}

bool FirmwareEmulator::dropped(uint64_t seq) {
  bool hit = false;
  for (std::size_t i = 0; i < faults_.drop_samples.size(); ++i) {
    const auto& [first, count] = faults_.drop_samples[i];
    if (seq >= first && seq < first + count) hit = true, ++stats_.drop_hits[i];
  }
  return hit;
}

void FirmwareEmulator::send_layout_sample(uint64_t seq, float x, float y, uint8_t status) {
  if (block_.empty()) block_seq_ = seq;
  block_.push_back({x, y, status});
  const auto n = static_cast<std::size_t>(opts_.stream->samples_per_frame());
  if (block_.size() < n) return;
  // The faults act on what the bus carries: a dropped sample takes its frames with it (all the
  // block's samples when they share a frame); channel c of drop_frames is the c-th frame of a
  // block (a message, or one multiplexer page of it).
  bool drop = false;
  for (std::size_t i = 0; i < n; ++i) drop = dropped(block_seq_ + i) || drop;  // every sample's hit counted
  frames_.clear();
  opts_.stream->encode(static_cast<uint32_t>(block_seq_), block_, frames_);
  block_.clear();
  if (drop) {
    stats_.samples_dropped += n;
    return;
  }
  const int copies = faults_.duplicate_samples.count(block_seq_) ? 2 : 1;
  for (int k = 0; k < copies; ++k)
    for (std::size_t c = 0; c < frames_.size(); ++c) {
      if (faults_.drop_frames.count({block_seq_, static_cast<int>(c)})) continue;
      const link::CanFdFrame& f = frames_[c];
      if (f.fd) {  // a CAN FD layout: the transport must carry FD (vcan with mtu 72, the in-process bus)
        if (silent()) continue;
        flush_sends();  // the classic frames queued before it leave first, as sent
        bus_.send_fd(f);
        ++stats_.frames_sent;
        continue;
      }
      link::CanFrame cf;
      cf.id = f.id;
      cf.extended = f.extended;
      cf.len = f.len;
      std::copy_n(f.data.begin(), f.len, cf.data.begin());
      send(cf);
    }
}

void FirmwareEmulator::send_sample(uint64_t seq, float x, float y, uint8_t status) {
  if (opts_.stream) return send_layout_sample(seq, x, y, status);
  if (dropped(seq)) {
    ++stats_.samples_dropped;
    return;
  }
  const int copies = faults_.duplicate_samples.count(seq) ? 2 : 1;
  for (int i = 0; i < copies; ++i) {
    if (!faults_.drop_frames.count({seq, 0}))
      send(link::encode(link::StreamHalf{link::Channel::X, static_cast<uint32_t>(seq), status, x}));
    if (!faults_.drop_frames.count({seq, 1}))
      send(link::encode(link::StreamHalf{link::Channel::Y, static_cast<uint32_t>(seq), status, y}));
  }
}

void FirmwareEmulator::handle_commands() {
  const CancelToken never;
  while (auto rx = bus_.receive(0, never)) {
    if (!opts_.commands) {  // no command channel: what the rig sends goes unanswered
      ++stats_.commands_ignored;
      continue;
    }
    const link::Decoded d = link::decode(rx->frame);
    const auto* c = std::get_if<link::Command>(&d.msg);
    if (!c) {
      ++stats_.bad_commands;  // malformed: a real MCU cannot answer what it cannot parse
      continue;
    }
    ++stats_.commands;
    const link::Response r = execute(*c);
    if (r.result != Result::Ok) ++stats_.bad_commands;
    send(link::encode(r));
  }
}

link::Response FirmwareEmulator::execute(const link::Command& c) {
  link::Response r;
  r.op = c.op;
  r.token = c.token;
  auto bad = [&r](Result why) {
    r.result = why;
    return r;
  };
  if (!link::known_op(static_cast<uint8_t>(c.op))) return bad(Result::UnknownOp);
  switch (c.op) {
    case Op::StartStream:
      if (loop_ || !burst_.empty()) return bad(Result::BadState);  // the loop test owns the DUT until its burst is out
      streaming_ = true;
      block_.clear();  // a block starts with the stream
      r.value = static_cast<uint32_t>(counter_);
      break;
    case Op::StopStream:
      streaming_ = false;
      r.value = static_cast<uint32_t>(counter_);
      break;
    case Op::FilterBegin: {
      const float rate = link::bits_f32(c.value);
      if (c.a0 > link::kMaxSections || !std::isfinite(rate) || !(rate > 0)) return bad(Result::BadArgument);
      staged_ = FilterConfig{};
      staged_.sections.assign(c.a0, Biquad{});
      staged_.rate_hz = rate;
      staged_have_.assign(static_cast<std::size_t>(c.a0) * 5, 0);
      staging_ = true;
      r.aux = c.a0;
      r.value = c.value;
      break;
    }
    case Op::FilterCoef: {
      if (!staging_) return bad(Result::BadState);
      const float v = link::bits_f32(c.value);
      if (c.a0 >= staged_.sections.size() || c.a1 >= 5 || !std::isfinite(v)) return bad(Result::BadArgument);
      Biquad& b = staged_.sections[c.a0];
      double* coef[5] = {&b.b0, &b.b1, &b.b2, &b.a1, &b.a2};
      *coef[c.a1] = v;
      staged_have_[static_cast<std::size_t>(c.a0) * 5 + c.a1] = 1;
      r.aux = static_cast<uint8_t>(c.a0 << 4 | c.a1);
      r.value = c.value;
      break;
    }
    case Op::FilterCommit: {
      if (!staging_) return bad(Result::BadState);
      const bool complete = std::all_of(staged_have_.begin(), staged_have_.end(), [](uint8_t h) { return h != 0; });
      const bool stable = std::all_of(staged_.sections.begin(), staged_.sections.end(), stable_section);
      if (!complete || !stable) return bad(Result::BadArgument);
      staged_.enabled = src_.filter().enabled;
      src_.set_filter(staged_);
      staging_ = false;
      r.aux = static_cast<uint8_t>(staged_.sections.size());
      break;
    }
    case Op::FilterGetInfo: {
      const FilterConfig f = src_.filter();
      r.aux = static_cast<uint8_t>(std::min<std::size_t>(f.sections.size(), 0x7F) | (f.enabled ? 0x80u : 0u));
      r.value = link::f32_bits(static_cast<float>(f.rate_hz));
      break;
    }
    case Op::FilterGetCoef: {
      const FilterConfig f = src_.filter();
      if (c.a0 >= f.sections.size() || c.a1 >= 5) return bad(Result::BadArgument);
      const Biquad& b = f.sections[c.a0];
      const double coef[5] = {b.b0, b.b1, b.b2, b.a1, b.a2};
      r.aux = static_cast<uint8_t>(c.a0 << 4 | c.a1);
      r.value = link::f32_bits(static_cast<float>(coef[c.a1]));
      break;
    }
    case Op::FilterEnable: {
      if (c.a0 > 1) return bad(Result::BadArgument);
      FilterConfig f = src_.filter();
      f.enabled = c.a0 == 1;
      src_.set_filter(f);
      r.aux = c.a0;
      break;
    }
    case Op::GetSerial: {
      const std::string s = src_.serial().substr(0, link::kMaxSerial);
      if (c.a0 * 4u >= std::max<std::size_t>(s.size(), 1)) {
        if (c.a0 != 0) return bad(Result::BadArgument);
      }
      r.aux = static_cast<uint8_t>(s.size());
      for (unsigned i = 0; i < 4; ++i) {
        const std::size_t k = c.a0 * 4u + i;
        if (k < s.size()) r.value |= static_cast<uint32_t>(static_cast<uint8_t>(s[k])) << (8 * i);
      }
      break;
    }
    case Op::GetVersion:
      r.aux = static_cast<uint8_t>(opts_.version_major);
      r.value = static_cast<uint32_t>(opts_.version_minor & 0xFFFF) | static_cast<uint32_t>(opts_.version_patch & 0xFFFF) << 16;
      break;
    case Op::GetTemperature:
      r.value = link::f32_bits(static_cast<float>(src_.temperature_c()));
      break;
    case Op::LoopTest:
      return start_loop_test(c);
  }
  return r;
}

link::Response FirmwareEmulator::start_loop_test(const link::Command& c) {
  link::Response r{c.op, c.token, Result::Ok, c.a0, 0};
  const int spo = src_.loop_steps_per_output();
  if (!opts_.loop_test || spo <= 0) {
    r.result = Result::UnknownOp;  // this firmware has no loop test
    return r;
  }
  if (streaming_ || loop_ || !burst_.empty()) {
    r.result = Result::BadState;
    return r;
  }
  const int ms = c.a1 == 0 ? link::loop_cmd::kDefaultRecordMs : c.a1;
  const float amp = link::bits_f32(c.value);
  if (c.a0 != link::loop_cmd::kStep || ms < link::loop_cmd::kMinRecordMs || ms > link::loop_cmd::kMaxRecordMs ||
      !std::isfinite(amp) || amp == 0 || std::abs(amp) > link::loop_cmd::kMaxAmplitudeG) {
    r.result = Result::BadArgument;
    return r;
  }
  LoopRun run;
  run.token = c.token;
  run.amplitude_g = amp;
  run.quiet_ticks = ms;  // one record length without test torque first
  run.record_ticks = ms;
  run.pre_ticks = std::max(1, ms / 10);
  const auto n = static_cast<std::size_t>(ms) * static_cast<std::size_t>(spo);
  run.x.assign(n, 0.0f);
  run.y.assign(n, 0.0f);
  loop_ = std::move(run);
  r.value = static_cast<uint32_t>(n);
  return r;
}

void FirmwareEmulator::loop_test_period() {
  LoopRun& run = *loop_;
  const auto spo = static_cast<std::size_t>(src_.loop_steps_per_output());
  const std::size_t at = static_cast<std::size_t>(run.done_ticks) * spo;
  const double torque = run.done_ticks >= run.pre_ticks ? run.amplitude_g : 0.0;
  run.saturated = src_.next_under_test(torque, std::span(run.x).subspan(at, spo), std::span(run.y).subspan(at, spo)) ||
                  run.saturated;
  if (++run.done_ticks == run.record_ticks) queue_burst();
}

void FirmwareEmulator::queue_burst() {
  const LoopRun& run = *loop_;
  const auto spo = static_cast<std::size_t>(src_.loop_steps_per_output());
  std::size_t place = 0;
  auto queue = [&](const link::CanFrame& f) {
    if (!faults_.drop_burst_frames.count(place++)) burst_.push_back(f);
  };
  for (std::size_t i = 0; i < run.x.size(); ++i) {
    queue(link::encode(link::LoopData{static_cast<uint16_t>(i), link::Channel::X, run.token, run.x[i]}));
    queue(link::encode(link::LoopData{static_cast<uint16_t>(i), link::Channel::Y, run.token, run.y[i]}));
  }
  link::LoopEnd e;
  e.token = run.token;
  e.status = run.saturated ? link::loop_cmd::kSaturated : 0;
  e.samples = static_cast<uint16_t>(run.x.size());
  e.pre_samples = static_cast<uint16_t>(static_cast<std::size_t>(run.pre_ticks) * spo);
  e.rate_hz = static_cast<uint16_t>(std::lround(src_.output_rate_hz() * static_cast<double>(spo)));
  queue(link::encode(e));
  ++stats_.loop_tests;
  loop_.reset();
}

void FirmwareEmulator::start_realtime() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] {
    using clk = std::chrono::steady_clock;
    auto t0 = clk::now();
    uint64_t done = 0;
    while (!stop_) {
      const auto due = static_cast<uint64_t>((clk::now() - t0) / std::chrono::nanoseconds(kFirmwareTickNs));
      // A wake-up more than 1 s late (suspended process) restarts the schedule
      // rather than bursting a second of samples.
      if (due > done + 1000) {
        t0 = clk::now();
        done = 0;
        continue;
      }
      try {
        for (; done < due && !stop_; ++done) {
          std::lock_guard lk(mu_);
          tick();
          flush_sends();  // in real time each tick's frames leave at their tick
        }
      } catch (const std::exception&) {
        // A transport error (interface went down): keep ticking, a real MCU does.
        ++done;
      }
      std::this_thread::sleep_until(t0 + std::chrono::nanoseconds(kFirmwareTickNs) * (done + 1));
    }
  });
}

void FirmwareEmulator::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

}  // namespace rig::plant
