// The rig-side DUT client: rig::DutLink over any CanTransport.
// It waits only by calling the transport's receive(timeout), and reads time off the
// rig::Clock it is given. One path for real and simulated time: in emulation the
// lockstep transport (inprocess_bus.hpp) owns simulated time, and its receive steps
// the world instead of waiting, so nothing here knows whether time is simulated.
#pragma once
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

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
  // [dut] loop_test = false: the rig does not ask this DUT for the loop test (its firmware has
  // none, or it must not be disturbed); loop_test() then answers "not supported".
  bool loop_test = true;
  // [dut] commands = false: the DUT has no command channel; it streams from power-on and
  // ignores the rig's commands. The link sends none: start_stream() joins the running stream
  // (frames older than the call are dropped), stop_stream() stops listening.
  bool commands = true;
  // A DBC-described stream ([dut] dbc + [dut.stream]). Null: the rig protocol's stream
  // (docs/rig-dut.dbc with rig_protocol_stream()), decoded by the codec: the same parts,
  // checked in tests/link/test_dbc_stream.cpp.
  std::shared_ptr<const DbcStreamDecoder> stream;
};

// Why the link refuses the loop test from its options alone, without asking the DUT (no command
// channel, or [dut] loop_test = false); "" where it asks the DUT. CanDutLink::loop_test answers
// with it, and a resume that opens no device gives the same answer (app/backends.hpp).
std::string loop_test_refused_by(const LinkOptions& o);

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
  LoopTestResponse loop_test(const LoopTestRequest& request, const CancelToken& cancel) override;
  DutCommandChannel command_channel() const override;

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
  void dispatch(const RxFrame& f);  // state_mu_ held
  // Whether a stream frame received at rx_t_s (transport clock) is taken; ends the join on the
  // first fresh frame carrying an x. Called with state_mu_ held.
  bool accept_stream_frame(double rx_t_s, bool has_x);
  // Waits up to `budget_s` for a frame on the transport and dispatches it and every frame
  // queued behind it (one batch, one lock). Returns whether a frame was dispatched.
  bool pump(double budget_s, const CancelToken& cancel);
  [[noreturn]] void fail_silent(double silent_s);
  // Sends `c` (a fresh token per attempt) and returns the DUT's answer whatever its result;
  // throws HardwareError only when no answer comes within the attempts. Called with io_mu_ held.
  Response exchange(Command c, const CancelToken& cancel);
  // One LOOP_TEST step: the command, then its burst up to the end marker (loop_test()).
  LoopStepRecord loop_step(const LoopTestRequest& request, const CancelToken& cancel, double& rate_hz);

  std::unique_ptr<CanTransport> transport_;
  Clock& clock_;
  LinkOptions opts_;
  std::mutex io_mu_;             // one blocking operation at a time (read or command)
  mutable std::mutex state_mu_;  // guards the fields below, read by stats() from any thread
  StreamReassembler reasm_;
  std::vector<StreamPart> parts_;  // scratch of dispatch()
  std::vector<RxFrame> rx_;        // scratch of pump() (io_mu_ held)
  std::deque<Response> responses_;
  std::optional<Heartbeat> heartbeat_;
  uint64_t malformed_ = 0;
  double last_stream_rx_ = 0;    // clock time the last stream frame arrived
  bool streaming_ = false;
  // Without commands: joining a stream that runs from power-on. Frames received before
  // join_t_ (transport clock) are stale; the first sample taken is the first whose x arrives,
  // so that a sample cut in half by the join is not counted as lost.
  bool joining_ = false;
  double join_t_ = 0;
  uint8_t token_ = 0;
  // The loop test's burst being received (token of its LOOP_TEST; frames of other tokens are stale).
  std::optional<uint8_t> loop_token_;
  std::vector<LoopData> loop_rx_;
  std::optional<LoopEnd> loop_end_;
};

}  // namespace rig::link
