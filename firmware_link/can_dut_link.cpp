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
    {can_id::kLoopData, 0x7FE},  // 0x180 and 0x181: the loop test's burst and its end
    {can_id::kHeartbeat, 0x7FF},
};

std::string hex_op(Op op) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s (op 0x%02X)", to_string(op), static_cast<unsigned>(op));
  return buf;
}

// A firmware that answers UNKNOWN_OP to LOOP_TEST: not a fault, the DUT has no loop test.
struct LoopTestUnsupported {};

constexpr const char* kNoCommands = "the DUT has no command channel (commands = false: [dut] of the hardware file, or [plant.firmware] of an emulated plant)";

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
  if (!streaming_ || !opts_.commands) return;
  try {
    transport_->send(encode(Command{Op::StopStream, 0, 0, 0, 0}));
  } catch (...) {
  }
}

std::string CanDutLink::describe() const {
  char buf[160];
  if (!opts_.commands) {
    std::snprintf(buf, sizeof buf, "CAN DUT link on %s (silence limit %.0f ms, no command channel)",
                  transport_->name().c_str(), opts_.silence_s * 1e3);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "CAN DUT link on %s (silence limit %.0f ms, command timeout %.0f ms x %d)",
                transport_->name().c_str(), opts_.silence_s * 1e3, opts_.command_timeout_s * 1e3,
                opts_.command_attempts);
  return buf;
}

bool CanDutLink::accept_stream_frame(double rx_t_s, bool has_x) {
  if (!streaming_) return false;  // frames still in flight after a stop are stale
  if (!joining_) return true;
  if (rx_t_s < join_t_ || !has_x) return false;
  joining_ = false;
  return true;
}

void CanDutLink::dispatch(const RxFrame& rx) {
  if (opts_.stream) {  // a DBC-described stream: its frames before the protocol's
    parts_.clear();
    std::string err;
    if (rx.fd ? opts_.stream->decode(*rx.fd, parts_, &err) : opts_.stream->decode(rx.frame, parts_, &err)) {
      if (!err.empty()) {
        ++malformed_;
        return;
      }
      const bool has_x =
          std::any_of(parts_.begin(), parts_.end(), [](const StreamPart& p) { return p.channel == Channel::X; });
      if (!accept_stream_frame(rx.t_s, has_x)) return;  // stale frames do not count as the stream's life either
      last_stream_rx_ = clock_.now_s() - std::max(0.0, transport_->now_s() - rx.t_s);  // as below
      for (const StreamPart& p : parts_) reasm_.push_part(p);
      return;
    }
  }
  if (rx.fd) return;  // the rig protocol is classic CAN: an FD frame is another node's
  const Decoded d = decode(rx.frame);
  if (!d.error.empty()) {
    ++malformed_;
    return;
  }
  if (const auto* s = std::get_if<StreamHalf>(&d.msg)) {
    if (opts_.commands || accept_stream_frame(rx.t_s, s->channel == Channel::X)) {
      // When it arrived, not when the client got round to it: its age on the transport's clock.
      last_stream_rx_ = clock_.now_s() - std::max(0.0, transport_->now_s() - rx.t_s);
      if (streaming_) reasm_.push(*s);  // frames still in flight after a stop are stale
    }
  } else if (const auto* r = std::get_if<Response>(&d.msg)) {
    responses_.push_back(*r);
    if (responses_.size() > 32) responses_.pop_front();
  } else if (const auto* h = std::get_if<Heartbeat>(&d.msg)) {
    heartbeat_ = *h;
  } else if (const auto* l = std::get_if<LoopData>(&d.msg)) {
    if (loop_token_ && l->token == *loop_token_) loop_rx_.push_back(*l);
  } else if (const auto* e = std::get_if<LoopEnd>(&d.msg)) {
    if (loop_token_ && e->token == *loop_token_) loop_end_ = *e;
  }
}

bool CanDutLink::pump(double budget_s, const CancelToken& cancel) {
  // Every queued frame at once: the same frames in the same order as one receive() per
  // call, with the transport's and the state's lock taken once per batch (issue 17). The
  // batch is bounded so that a stream never starves the caller's checks between batches.
  constexpr std::size_t kMaxBatch = 512;
  rx_.clear();
  if (transport_->receive_batch(rx_, kMaxBatch, budget_s, cancel) == 0) return false;
  std::lock_guard lk(state_mu_);
  for (const RxFrame& f : rx_) dispatch(f);
  return true;
}

Response CanDutLink::exchange(Command c, const CancelToken& cancel) {
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
          return r;
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

Response CanDutLink::command(Command c, const CancelToken& cancel) {
  if (!opts_.commands)
    throw ConfigError("DUT on " + transport_->name() + ": cannot send " + hex_op(c.op) + ": " + kNoCommands);
  std::lock_guard io(io_mu_);
  const Response r = exchange(c, cancel);
  if (r.result == Result::Ok) return r;
  const std::string msg = "DUT on " + transport_->name() + " rejected " + hex_op(c.op) + ": " + to_string(r.result);
  if (r.result == Result::BadArgument) throw ConfigError(msg);
  throw HardwareError(msg);
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

DutCommandChannel CanDutLink::command_channel() const {
  if (opts_.commands) return {};
  return {false, kNoCommands};
}

void CanDutLink::start_stream(const CancelToken& cancel) {
  if (!opts_.commands) {  // the DUT streams from power-on: join it from now on
    std::lock_guard lk(state_mu_);
    reasm_.restart();
    streaming_ = true;
    joining_ = true;
    join_t_ = transport_->now_s();
    last_stream_rx_ = clock_.now_s();
    return;
  }
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
  if (!opts_.commands) {  // nothing to tell the DUT: stop listening
    std::lock_guard lk(state_mu_);
    reasm_.flush();
    streaming_ = false;
    joining_ = false;
    return;
  }
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

std::string loop_test_refused_by(const LinkOptions& o) {
  if (!o.commands) return std::string("no loop test: ") + kNoCommands;
  if (!o.loop_test) return "loop test switched off for this DUT ([dut] loop_test = false in the hardware file)";
  return "";
}

LoopTestResponse CanDutLink::loop_test(const LoopTestRequest& rq, const CancelToken& cancel) {
  LoopTestResponse out;
  if (out.reason = loop_test_refused_by(opts_); !out.reason.empty()) return out;
  if (!(std::abs(rq.amplitude_g) > 0) || std::abs(rq.amplitude_g) > loop_cmd::kMaxAmplitudeG)
    throw ConfigError("loop test amplitude " + std::to_string(rq.amplitude_g) + " g: must be non-zero and at most " +
                      std::to_string(loop_cmd::kMaxAmplitudeG) + " g");
  if (rq.steps < 1) throw ConfigError("loop test needs at least one step, not " + std::to_string(rq.steps));
  const double ms = std::round(rq.record_s * 1e3);
  if (!(ms >= loop_cmd::kMinRecordMs && ms <= loop_cmd::kMaxRecordMs))
    throw ConfigError("loop test record " + std::to_string(rq.record_s) + " s: must be " +
                      std::to_string(loop_cmd::kMinRecordMs) + ".." + std::to_string(loop_cmd::kMaxRecordMs) + " ms");
  if (streaming_) throw HardwareError("loop test on " + transport_->name() + " asked for while the stream runs");
  out.supported = true;
  out.amplitude_g = rq.amplitude_g;
  try {
    for (int k = 0; k < rq.steps; ++k) out.steps.push_back(loop_step(rq, cancel, out.rate_hz));
  } catch (const LoopTestUnsupported&) {
    return {false, "the DUT's firmware has no loop test (LOOP_TEST answered UNKNOWN_OP)", 0, 0, {}};
  }
  return out;
}

LoopStepRecord CanDutLink::loop_step(const LoopTestRequest& rq, const CancelToken& cancel, double& rate_hz) {
  std::lock_guard io(io_mu_);
  const auto ms = static_cast<uint8_t>(std::lround(rq.record_s * 1e3));
  const Command c{Op::LoopTest, 0, loop_cmd::kStep, ms, f32_bits(static_cast<float>(rq.amplitude_g))};
  // The burst is accepted from the first frame after the command: arm before sending.
  {
    std::lock_guard lk(state_mu_);
    loop_token_ = static_cast<uint8_t>(token_ + 1);
    loop_rx_.clear();
    loop_end_.reset();
  }
  struct Disarm {
    CanDutLink& l;
    ~Disarm() {
      std::lock_guard lk(l.state_mu_);
      l.loop_token_.reset();
      l.loop_rx_.clear();
    }
  } disarm{*this};
  const Response r = exchange(c, cancel);
  if (r.result == Result::UnknownOp) throw LoopTestUnsupported{};
  if (r.result != Result::Ok)
    throw HardwareError("DUT on " + transport_->name() + " rejected " + hex_op(c.op) + ": " + to_string(r.result));
  {
    std::lock_guard lk(state_mu_);
    loop_token_ = r.token;  // a re-sent command has its own token
  }
  const std::size_t n = r.value;
  // The step's nominal device time (quiet wait, record, burst at the bus's pace); allow twice
  // that and a second.
  const double budget_s = 2 * loop_step_nominal_s(rq.record_s, n) + 1.0;
  const double deadline = clock_.now_s() + budget_s;
  for (;;) {
    {
      std::lock_guard lk(state_mu_);
      if (loop_end_) break;
    }
    if (clock_.now_s() >= deadline) {
      std::lock_guard lk(state_mu_);
      char buf[200];
      std::snprintf(buf, sizeof buf, "loop test on %s: no end of burst within %.2f s (%zu of %zu frames received)",
                    transport_->name().c_str(), budget_s, loop_rx_.size(), 2 * n);
      throw HardwareError(buf);
    }
    cancel.throw_if_requested();
    pump(0.005, cancel);
  }
  std::lock_guard lk(state_mu_);
  const LoopEnd e = *loop_end_;
  if (e.status & loop_cmd::kAborted)
    throw HardwareError("loop test on " + transport_->name() + ": the DUT aborted the test");
  if (e.samples != n || e.pre_samples >= n || e.rate_hz == 0)
    throw HardwareError("loop test on " + transport_->name() + ": end marker says " + std::to_string(e.samples) +
                        " samples (" + std::to_string(e.pre_samples) + " before the step) at " +
                        std::to_string(e.rate_hz) + " Hz, the command announced " + std::to_string(n));
  if (rate_hz != 0 && rate_hz != e.rate_hz)
    throw HardwareError("loop test on " + transport_->name() + ": the loop rate changed between steps");
  rate_hz = e.rate_hz;
  LoopStepRecord rec;
  rec.pre_samples = e.pre_samples;
  rec.saturated = (e.status & loop_cmd::kSaturated) != 0;
  rec.x.assign(n, std::nan(""));
  rec.y.assign(n, std::nan(""));
  for (const LoopData& d : loop_rx_)
    if (d.index < n) (d.channel == Channel::X ? rec.x : rec.y)[d.index] = d.value_g;
  std::size_t lost = 0, first = n;
  for (std::size_t i = 0; i < n; ++i)
    if (std::isnan(rec.x[i]) || std::isnan(rec.y[i])) {
      ++lost;
      first = std::min(first, i);
    }
  if (lost > 0)
    throw HardwareError("loop test on " + transport_->name() + ": " + std::to_string(lost) + " of " +
                        std::to_string(n) + " samples lost in the burst (first at index " + std::to_string(first) + ")");
  return rec;
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
