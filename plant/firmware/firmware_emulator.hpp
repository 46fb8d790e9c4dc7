// The DUT's firmware, emulated: answers the CAN protocol's commands and streams
// the output of a DutSource (the emulated accelerometer) at 1 kHz, plus a
// 10 Hz heartbeat. Two ways to run it:
//  - lockstep: the world calls step(dt) (simulated time; no thread, no sleeping);
//  - real time: start_realtime() runs its own thread paced by the wall clock
//    (`rig plant serve --can IFACE`, the guest-kernel tests).
// Fault injection (tests): drop chosen samples or single frames, duplicate
// samples, go silent.
#pragma once
#include <atomic>
#include <cstdint>
#include <deque>
#include <optional>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "firmware_link/can_transport.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "plant/emulated/dut_source.hpp"

namespace rig::plant {

// The firmware's tick: one output sample per tick, 1 ms (1 kHz), as the protocol's DUT streams.
inline constexpr int64_t kFirmwareTickNs = 1'000'000;

struct FirmwareOptions {
  int version_major = 1, version_minor = 4, version_patch = 0;
  double heartbeat_hz = 10.0;
  uint32_t first_seq = 0;  // the 32-bit sample counter at power-on
  bool loop_test = true;   // false: a firmware without LOOP_TEST (it answers UNKNOWN_OP)
  // false: a firmware without a command channel: it streams from power-on (construction) and
  // reads nothing from the bus (docs/can-protocol.md "DUTs without commands").
  bool commands = true;
  // The stream's layout as a DBC describes it ([plant.firmware] dbc + stream): null, the rig
  // protocol's two frames per sample. With N samples per frame the firmware sends a block of
  // N samples' frames every N output periods.
  std::shared_ptr<const link::DbcStreamEncoder> stream;
};

struct FirmwareFaults {
  // Samples (32-bit counter values) never sent: both frames are dropped.
  std::vector<std::pair<uint64_t, uint64_t>> drop_samples;  // (first, count)
  // Single frames dropped: (sample, channel 0 = X / 1 = Y).
  std::set<std::pair<uint64_t, int>> drop_frames;
  // Samples sent twice (both frames repeated right after the originals).
  std::set<uint64_t> duplicate_samples;
  // From this sample on the firmware sends nothing at all (stream, heartbeat, answers).
  std::optional<uint64_t> silent_from;
  // Frames of every loop test's burst never sent, by their place in the burst (0 = the first).
  std::set<std::size_t> drop_burst_frames;
};

struct FirmwareStats {
  uint64_t samples = 0;         // output periods produced while streaming
  uint64_t frames_sent = 0;
  uint64_t samples_dropped = 0; // by fault injection
  // Per FirmwareFaults::drop_samples entry: how many of its samples were due while streaming
  // (0: the fault never acted; the stream was off over its whole range).
  std::vector<uint64_t> drop_hits;
  uint64_t commands = 0;
  uint64_t bad_commands = 0;
  uint64_t loop_tests = 0;      // loop tests completed (their bursts queued)
  uint64_t commands_ignored = 0; // frames a firmware without commands left unanswered
};

class FirmwareEmulator {
 public:
  FirmwareEmulator(DutSource& source, link::CanTransport& bus, FirmwareOptions opts = {});
  ~FirmwareEmulator();
  FirmwareEmulator(const FirmwareEmulator&) = delete;
  FirmwareEmulator& operator=(const FirmwareEmulator&) = delete;

  // Lockstep: advance the firmware by dt seconds of simulated time. Each 1 ms
  // tick handles the commands received, then produces one sample.
  void step(double dt_s);

  // Real time: a thread ticks at 1 kHz of wall time (catching up after a late
  // wake-up, so the average rate holds). stop() joins it.
  void start_realtime();
  void stop();
  bool running() const { return thread_.joinable(); }

  void set_faults(FirmwareFaults f);
  FirmwareStats stats() const;
  bool streaming() const { return streaming_; }
  const FirmwareOptions& options() const { return opts_; }
  uint64_t sample_counter() const;  // the next sample's counter value

 private:
  void tick();  // one output period; the caller holds mu_ and flushes the frames it queued
  void handle_commands();
  link::Response execute(const link::Command& c);
  void send_sample(uint64_t seq, float x, float y, uint8_t status);
  // A DBC layout: collects samples and sends the frames of each full block.
  void send_layout_sample(uint64_t seq, float x, float y, uint8_t status);
  bool dropped(uint64_t seq);  // counts the hit (stats_.drop_hits)
  void send(const link::CanFrame& f);  // queues it for the end of the tick or slice (flush_sends)
  void flush_sends();                   // the frames queued, in order, in one batch
  bool silent() const;
  link::Response start_loop_test(const link::Command& c);
  void loop_test_period();  // one output period of a running loop test
  void queue_burst();       // the finished record as DUT_LOOP_DATA frames and the end marker

  // A loop test in progress: quiet (no test torque, the loop settles from anything before),
  // then the record: pre_ticks without torque, the rest with it.
  struct LoopRun {
    uint8_t token = 0;
    double amplitude_g = 0;
    int quiet_ticks = 0, pre_ticks = 0, record_ticks = 0, done_ticks = 0;
    std::vector<float> x, y;
    bool saturated = false;
  };

  DutSource& src_;
  link::CanTransport& bus_;
  FirmwareOptions opts_;
  mutable std::mutex mu_;  // the firmware state below (tick vs. set_faults/stats from other threads)
  FirmwareFaults faults_;
  FirmwareStats stats_;
  uint64_t counter_;
  double time_acc_ = 0;  // simulated time not yet turned into ticks
  uint64_t ticks_ = 0;
  uint8_t hb_counter_ = 0;
  std::atomic<bool> streaming_{false};
  // FILTER_BEGIN .. FILTER_COMMIT staging area.
  FilterConfig staged_;
  std::vector<uint8_t> staged_have_;  // one bit per coefficient (5 per section)
  bool staging_ = false;
  std::optional<LoopRun> loop_;
  std::vector<link::StreamSample> block_;  // a DBC layout's samples not yet sent
  uint64_t block_seq_ = 0;                 // the first one's counter
  std::vector<link::CanFdFrame> frames_;   // scratch of send_layout_sample
  std::deque<link::CanFrame> burst_;  // sent at the bus's pace, a few frames per tick
  std::vector<link::CanFrame> tx_;    // frames queued (send() .. flush_sends())
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

}  // namespace rig::plant
