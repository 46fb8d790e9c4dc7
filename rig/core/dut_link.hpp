// DUT link seam: the DUT's firmware streams samples and answers commands.
// Real backend: CAN (firmware_link/, SocketCAN). Emulated: the same CAN client to
// the firmware emulator on an in-process bus (plant/emulated).
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "rig/core/filter_config.hpp"  // Biquad, FilterConfig: the filter the link sets
#include "rig/core/cancel.hpp"
#include "rig/core/types.hpp"

namespace rig {

struct DutInfo {
  std::string serial;
  std::string firmware;
  double temperature_c = 0.0;
  double output_rate_hz = 1000.0;
};

// Stream health counted by the link's reassembly (sequence numbers).
struct LinkStats {
  uint64_t received = 0;    // samples delivered
  uint64_t gaps = 0;        // gap events
  uint64_t lost = 0;        // samples missing in gaps
  uint64_t duplicates = 0;  // dropped duplicates / late frames
  std::vector<std::pair<uint64_t, uint64_t>> gap_list;  // (first missing seq, count), first 1000
};

// The loop test (docs/can-protocol.md "Loop test"): the DUT injects a test torque inside its
// feedback loop -- a step equivalent to `amplitude_g` of input acceleration -- and records the
// loop's response at its inner rate. `steps` tests are run one after another.
struct LoopTestRequest {
  double amplitude_g = 1.0;  // docs/method.md: the settling time is quoted for a 1 g step
  int steps = 5;             // repeated steps: their scatter is the figures' uncertainty
  // Per step, the step after a tenth of it. 100 ms: the loop's integrator creeps for tens of
  // ms after the step, and the final value is read from the record's last fifth.
  double record_s = 0.1;
};
// A loop test's burst leaves at the pace of the 1 Mbit/s bus: 8-byte frames of at most 135 bits
// (docs/can-protocol.md, "Bus load"), about 7 per ms.
inline constexpr double kLoopBurstFramesPerS = 7000.0;
// Nominal device time of one loop-test step of `samples` samples (docs/can-protocol.md,
// DUT_LOOP): the firmware waits one record length for the loop to be quiet, records one, then
// sends 2 frames per sample and the end marker at the bus's pace.
inline double loop_step_nominal_s(double record_s, std::size_t samples) {
  return 2 * record_s + static_cast<double>(2 * samples + 1) / kLoopBurstFramesPerS;
}
// One step as the DUT recorded it, at the loop's rate: x the loop's output, y the same through
// the output filter the DUT is configured with; the first `pre_samples` precede the step.
struct LoopStepRecord {
  std::vector<double> x, y;
  std::size_t pre_samples = 0;
  bool saturated = false;  // the DUT's loop saturated during the record (its PWM duty or, in the emulated firmware, its pick-off ADC clipped)
};
struct LoopTestResponse {
  bool supported = false;  // false: the DUT (or the rig's configuration) has no loop test
  std::string reason;      // why not, when !supported
  double rate_hz = 0;      // the loop rate the records are sampled at
  double amplitude_g = 0;
  std::vector<LoopStepRecord> steps;
};

// Whether the DUT's firmware takes commands. A DUT without a command channel streams from
// power-on and answers nothing: the rig can then neither identify it, set its output filter
// nor run its loop test (docs/can-protocol.md "DUTs without commands").
struct DutCommandChannel {
  bool available = true;
  std::string reason;  // why not, when !available
};

class DutLink {
 public:
  virtual ~DutLink() = default;
  virtual DutInfo info(const CancelToken& cancel) = 0;
  virtual void start_stream(const CancelToken& cancel) = 0;
  virtual void stop_stream() noexcept = 0;  // safe-state path: never throws
  // Fills `out` with the next samples of the stream, in sequence order. Returns
  // the number written (== out.size() unless the stream is silent longer than
  // the link's silence limit, which throws HardwareError). Samples after a gap
  // carry sample_status::kGapBefore.
  virtual std::size_t read(std::span<Sample> out, const CancelToken& cancel) = 0;
  virtual void set_filter(const FilterConfig& f, const CancelToken& cancel) = 0;
  virtual FilterConfig get_filter(const CancelToken& cancel) = 0;
  virtual LinkStats stats() const = 0;
  virtual void reset_stats() = 0;
  virtual std::string describe() const = 0;
  // Runs the loop test; bounded in time and cancellable. A DUT without one answers
  // {supported = false, reason}; a test started but not completed (timeout, frames lost)
  // throws HardwareError. Only while the stream is stopped.
  virtual LoopTestResponse loop_test(const LoopTestRequest& /*request*/, const CancelToken& /*cancel*/) {
    return {false, describe() + " has no loop test", 0, 0, {}};
  }
  // Without a command channel, info(), set_filter() and get_filter() throw ConfigError,
  // start_stream() only starts listening and loop_test() answers "not supported".
  virtual DutCommandChannel command_channel() const { return {}; }
};

}  // namespace rig
