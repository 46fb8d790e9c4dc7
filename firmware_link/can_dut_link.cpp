#include "firmware_link/can_dut_link.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rig/core/errors.hpp"

namespace rig::link {

namespace {

// Only the DUT's frames reach the client (the kernel filters them on SocketCAN).
constexpr CanFilter kRxFilters[] = {
    {can_id::kResponse, 0x7FF},
    {can_id::kStreamX, 0x7FE},  // 0x100 and 0x101
    {can_id::kHeartbeat, 0x7FF},
};

std::string hex_op(Op op) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s (op 0x%02X)", to_string(op), static_cast<unsigned>(op));
  return buf;
}

}  // namespace

CanDutLink::CanDutLink(std::unique_ptr<CanTransport> transport, Clock& clock, LinkOptions opts)
    : transport_(std::move(transport)),
      clock_(clock),
      opts_(opts),
      reasm_(opts.stream ? opts.stream->make_reassembler(opts.reorder_window) : StreamReassembler(opts.reorder_window)) {
  std::vector<CanFilter> filters(std::begin(kRxFilters), std::end(kRxFilters));
  if (opts_.stream)
    for (const CanFilter& f : opts_.stream->filters()) filters.push_back(f);
  transport_->set_filters(filters);
}

CanDutLink::~CanDutLink() {
  // Fire-and-forget: waiting here could step a (simulated) world that is already gone.
  if (!streaming_) return;
  try {
    transport_->send(encode(Command{Op::StopStream, 0, 0, 0, 0}));
  } catch (...) {
  }
}

std::string CanDutLink::describe() const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "CAN DUT link on %s (silence limit %.0f ms, command timeout %.0f ms x %d)",
                transport_->name().c_str(), opts_.silence_s * 1e3, opts_.command_timeout_s * 1e3,
                opts_.command_attempts);
  return buf;
}

void CanDutLink::dispatch(const RxFrame& rx) {
  if (opts_.stream) {  // a DBC-described stream: its frames before the protocol's
    parts_.clear();
    std::string err;
    if (opts_.stream->decode(rx.frame, parts_, &err)) {
      std::lock_guard lk(state_mu_);
      if (!err.empty()) {
        ++malformed_;
        return;
      }
      last_stream_rx_ = opts_.frame_time_is_clock_time ? rx.t_s : clock_.now_s();
      if (streaming_)
        for (const StreamPart& p : parts_) reasm_.push_part(p);
      return;
    }
  }
  const Decoded d = decode(rx.frame);
  std::lock_guard lk(state_mu_);
  if (!d.error.empty()) {
    ++malformed_;
    return;
  }
  if (const auto* s = std::get_if<StreamHalf>(&d.msg)) {
    last_stream_rx_ = opts_.frame_time_is_clock_time ? rx.t_s : clock_.now_s();
    if (streaming_) reasm_.push(*s);  // frames still in flight after a stop are stale
  } else if (const auto* r = std::get_if<Response>(&d.msg)) {
    responses_.push_back(*r);
    if (responses_.size() > 32) responses_.pop_front();
  } else if (const auto* h = std::get_if<Heartbeat>(&d.msg)) {
    heartbeat_ = *h;
  }
}

bool CanDutLink::pump(double budget_s, const CancelToken& cancel) {
  if (!clock_.simulated()) {
    if (auto f = transport_->receive(std::min(budget_s, 0.02), cancel)) {
      dispatch(*f);
      return true;
    }
    return false;
  }
  if (auto f = transport_->receive(0, cancel)) {
    dispatch(*f);
    return true;
  }
  clock_.sleep_for(budget_s, cancel);  // steps the world: the emulator produces frames
  if (auto f = transport_->receive(0, cancel)) {
    dispatch(*f);
    return true;
  }
  return false;
}

Response CanDutLink::command(Command c, const CancelToken& cancel) {
  std::lock_guard io(io_mu_);
  for (int attempt = 1; attempt <= opts_.command_attempts; ++attempt) {
    {
      std::lock_guard lk(state_mu_);
      c.token = ++token_;
    }
    transport_->send(encode(c));
    const double deadline = clock_.now_s() + opts_.command_timeout_s;
    while (clock_.now_s() < deadline) {
      {
        std::lock_guard lk(state_mu_);
        auto it = std::find_if(responses_.begin(), responses_.end(),
                               [&](const Response& r) { return r.token == c.token && r.op == c.op; });
        if (it != responses_.end()) {
          const Response r = *it;
          responses_.erase(it);
          if (r.result == Result::Ok) return r;
          const std::string msg = "DUT on " + transport_->name() + " rejected " + hex_op(c.op) + ": " +
                                  to_string(r.result);
          if (r.result == Result::BadArgument) throw ConfigError(msg);
          throw HardwareError(msg);
        }
      }
      pump(0.001, cancel);
    }
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, " within %.0f ms (%d attempts)", opts_.command_timeout_s * 1e3,
                opts_.command_attempts);
  throw HardwareError("DUT on " + transport_->name() + " did not acknowledge " + hex_op(c.op) + buf);
}

DutInfo CanDutLink::info(const CancelToken& cancel) {
  DutInfo info;
  // Serial number: 4 characters per chunk, aux = its total length.
  Response r = command({Op::GetSerial, 0, 0, 0, 0}, cancel);
  const int len = std::min<int>(r.aux, kMaxSerial);
  std::string serial;
  for (int chunk = 0; chunk * 4 < len; ++chunk) {
    if (chunk > 0) r = command({Op::GetSerial, 0, static_cast<uint8_t>(chunk), 0, 0}, cancel);
    for (int i = 0; i < 4 && chunk * 4 + i < len; ++i) serial += static_cast<char>((r.value >> (8 * i)) & 0xFF);
  }
  info.serial = serial;
  r = command({Op::GetVersion, 0, 0, 0, 0}, cancel);
  info.firmware = std::to_string(r.aux) + "." + std::to_string(r.value & 0xFFFF) + "." + std::to_string(r.value >> 16);
  r = command({Op::GetTemperature, 0, 0, 0, 0}, cancel);
  info.temperature_c = bits_f32(r.value);
  info.output_rate_hz = opts_.stream ? opts_.stream->rate_hz() : 1000.0;  // the rig protocol's is 1 kHz
  return info;
}

void CanDutLink::start_stream(const CancelToken& cancel) {
  {
    std::lock_guard lk(state_mu_);
    reasm_.restart();
    streaming_ = true;  // accept stream frames from the first one after the ack
    last_stream_rx_ = clock_.now_s();
  }
  try {
    command({Op::StartStream, 0, 0, 0, 0}, cancel);
  } catch (...) {
    std::lock_guard lk(state_mu_);
    streaming_ = false;
    throw;
  }
  std::lock_guard lk(state_mu_);
  last_stream_rx_ = clock_.now_s();
}

void CanDutLink::stop_stream() noexcept {
  // Safe-state path: may run on another thread while read() blocks; then the
  // STOP is sent without waiting for its acknowledgement.
  std::unique_lock io(io_mu_, std::try_to_lock);
  if (!io.owns_lock()) {
    try {
      Command c{Op::StopStream, 0, 0, 0, 0};
      transport_->send(encode(c));
    } catch (...) {
    }
    std::lock_guard lk(state_mu_);
    streaming_ = false;
    return;
  }
  io.unlock();
  try {
    command({Op::StopStream, 0, 0, 0, 0}, CancelToken{});
  } catch (...) {  // never throws: the caller is already tearing down
  }
  std::lock_guard lk(state_mu_);
  reasm_.flush();
  streaming_ = false;
}

std::size_t CanDutLink::read(std::span<Sample> out, const CancelToken& cancel) {
  std::lock_guard io(io_mu_);
  std::size_t n = 0;
  for (;;) {
    double silent;
    {
      std::lock_guard lk(state_mu_);
      if (!streaming_) {  // never started, or stopped from another thread (abort path)
        cancel.throw_if_requested();
        throw HardwareError("DUT stream on " + transport_->name() + " is not running (read without start_stream)");
      }
      n += reasm_.pop(out.subspan(n));
      if (n == out.size()) return n;
      silent = clock_.now_s() - last_stream_rx_;
    }
    cancel.throw_if_requested();
    // Wait (or ask the world for) as much time as the missing samples need at
    // 1 kHz, at most 50 ms, and never past the silence limit, so that silence
    // is declared as soon as it exceeds the limit.
    const double need_s = static_cast<double>(out.size() - n) / 1000.0;
    const double to_limit = opts_.silence_s - silent + 0.001;
    if (pump(std::max(0.001, std::min({need_s, 0.05, to_limit})), cancel)) continue;
    // Silence is judged only when the transport had nothing queued: a caller
    // that came back late to read must not see its own delay as the DUT's.
    {
      std::lock_guard lk(state_mu_);
      silent = clock_.now_s() - last_stream_rx_;
    }
    if (silent >= opts_.silence_s) fail_silent(silent);
  }
}

void CanDutLink::fail_silent(double silent_s) {
  std::lock_guard lk(state_mu_);
  reasm_.flush();
  char buf[200];
  std::snprintf(buf, sizeof buf, "DUT stream on %s silent for %.0f ms (limit %.0f ms); next expected sample seq %llu, %llu received",
                transport_->name().c_str(), silent_s * 1e3, opts_.silence_s * 1e3,
                static_cast<unsigned long long>(reasm_.next_seq()),
                static_cast<unsigned long long>(reasm_.stats().received));
  throw HardwareError(buf);
}

void CanDutLink::set_filter(const FilterConfig& f, const CancelToken& cancel) {
  if (f.sections.size() > static_cast<std::size_t>(kMaxSections))
    throw ConfigError("output filter has " + std::to_string(f.sections.size()) + " sections; the DUT takes at most " +
                      std::to_string(kMaxSections));
  if (!(f.rate_hz > 0) || !std::isfinite(f.rate_hz))
    throw ConfigError("output filter rate_hz = " + std::to_string(f.rate_hz) + " must be positive");
  const auto sec_n = static_cast<uint8_t>(f.sections.size());
  command({Op::FilterBegin, 0, sec_n, 0, f32_bits(static_cast<float>(f.rate_hz))}, cancel);
  for (uint8_t s = 0; s < sec_n; ++s) {
    const Biquad& b = f.sections[s];
    const double c[5] = {b.b0, b.b1, b.b2, b.a1, b.a2};
    for (uint8_t i = 0; i < 5; ++i) {
      if (!std::isfinite(c[i]))
        throw ConfigError("output filter section " + std::to_string(s) + " coefficient " + std::to_string(i) +
                          " is not finite");
      command({Op::FilterCoef, 0, s, i, f32_bits(static_cast<float>(c[i]))}, cancel);
    }
  }
  command({Op::FilterCommit, 0, 0, 0, 0}, cancel);
  set_filter_enabled(f.enabled, cancel);
}

void CanDutLink::set_filter_enabled(bool on, const CancelToken& cancel) {
  command({Op::FilterEnable, 0, static_cast<uint8_t>(on ? 1 : 0), 0, 0}, cancel);
}

FilterConfig CanDutLink::get_filter(const CancelToken& cancel) {
  const Response info = command({Op::FilterGetInfo, 0, 0, 0, 0}, cancel);
  FilterConfig f;
  f.rate_hz = bits_f32(info.value);
  f.enabled = (info.aux & 0x80) != 0;
  const int n = info.aux & 0x7F;
  for (uint8_t s = 0; s < n; ++s) {
    double c[5];
    for (uint8_t i = 0; i < 5; ++i) c[i] = bits_f32(command({Op::FilterGetCoef, 0, s, i, 0}, cancel).value);
    f.sections.push_back({c[0], c[1], c[2], c[3], c[4]});
  }
  return f;
}

LinkStats CanDutLink::stats() const {
  std::lock_guard lk(state_mu_);
  return reasm_.stats();
}

void CanDutLink::reset_stats() {
  std::lock_guard lk(state_mu_);
  reasm_.reset_stats();
}

std::optional<Heartbeat> CanDutLink::last_heartbeat() const {
  std::lock_guard lk(state_mu_);
  return heartbeat_;
}

uint64_t CanDutLink::malformed_frames() const {
  std::lock_guard lk(state_mu_);
  return malformed_;
}

}  // namespace rig::link
