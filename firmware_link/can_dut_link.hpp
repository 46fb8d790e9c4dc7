// The rig-side DUT client: rig::DutLink over any CanTransport.
// Waiting is done on the rig::Clock it is given: with a RealClock it blocks on
// the transport in 20 ms slices; with a SimClock it polls the transport and,
// when the bus is empty, calls clock.sleep_for() so the (lockstep) world steps
// the firmware emulator, which produces the frames. No wall-clock sleeping in
// emulation.
#pragma once
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "firmware_link/can_transport.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "firmware_link/reassembly.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/dut_link.hpp"

namespace rig::link {

struct LinkOptions {
  double silence_s = 0.1;           // stream silent longer than this => HardwareError (issue 6: within 100 ms)
  double command_timeout_s = 0.25;  // per attempt
  int command_attempts = 3;         // commands are idempotent, so a lost frame is simply re-sent
  uint32_t reorder_window = 8;      // samples a half may arrive late before its sample is declared lost
  // The transport's frame timestamps are in the Clock's time base (the
  // in-process bus under a SimClock): silence is then measured from when the
  // last frame was produced, not from when the client got round to it.
  bool frame_time_is_clock_time = false;
  // A DBC-described stream ([dut] dbc + [dut.stream]). Null: the rig protocol's stream
  // (docs/rig-dut.dbc with rig_protocol_stream()), decoded by the codec: the same parts,
  // checked in tests/link/test_dbc_stream.cpp.
  std::shared_ptr<const DbcStreamDecoder> stream;
};

class CanDutLink final : public DutLink {
 public:
  CanDutLink(std::unique_ptr<CanTransport> transport, Clock& clock, LinkOptions opts = {});
  ~CanDutLink() override;

  DutInfo info(const CancelToken& cancel) override;
  void start_stream(const CancelToken& cancel) override;
  void stop_stream() noexcept override;
  std::size_t read(std::span<Sample> out, const CancelToken& cancel) override;
  void set_filter(const FilterConfig& f, const CancelToken& cancel) override;
  FilterConfig get_filter(const CancelToken& cancel) override;
  LinkStats stats() const override;
  void reset_stats() override;
  std::string describe() const override;

  // Beyond the seam (rig dut, tests).
  void set_filter_enabled(bool on, const CancelToken& cancel);
  // Sends one command and waits for its acknowledgement (re-sending on
  // timeout). A DUT that never answers => HardwareError; a rejected argument
  // => ConfigError; any other rejection => HardwareError.
  Response command(Command c, const CancelToken& cancel);
  std::optional<Heartbeat> last_heartbeat() const;
  TransportStats transport_stats() const { return transport_->stats(); }
  uint64_t malformed_frames() const;
  bool streaming() const { return streaming_; }

 private:
  void dispatch(const RxFrame& f);
  // Waits for traffic for up to `budget_s` (RealClock) or advances the
  // simulated world by `budget_s` when the bus is empty (SimClock).
  // Returns whether a frame was dispatched.
  bool pump(double budget_s, const CancelToken& cancel);
  [[noreturn]] void fail_silent(double silent_s);

  std::unique_ptr<CanTransport> transport_;
  Clock& clock_;
  LinkOptions opts_;
  std::mutex io_mu_;             // one blocking operation at a time (read or command)
  mutable std::mutex state_mu_;  // guards the fields below, read by stats() from any thread
  StreamReassembler reasm_;
  std::vector<StreamPart> parts_;  // scratch of dispatch()
  std::deque<Response> responses_;
  std::optional<Heartbeat> heartbeat_;
  uint64_t malformed_ = 0;
  double last_stream_rx_ = 0;    // clock time of the last stream frame
  bool streaming_ = false;
  uint8_t token_ = 0;
};

}  // namespace rig::link
