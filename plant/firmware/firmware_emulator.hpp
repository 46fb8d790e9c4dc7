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
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "firmware_link/can_transport.hpp"
#include "plant/emulated/dut_source.hpp"

namespace rig::plant {

struct FirmwareOptions {
  int version_major = 1, version_minor = 4, version_patch = 0;
  double heartbeat_hz = 10.0;
  uint32_t first_seq = 0;  // the 32-bit sample counter at power-on
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
};

struct FirmwareStats {
  uint64_t samples = 0;         // output periods produced while streaming
  uint64_t frames_sent = 0;
  uint64_t samples_dropped = 0; // by fault injection
  uint64_t commands = 0;
  uint64_t bad_commands = 0;
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
  uint64_t sample_counter() const;  // the next sample's counter value

 private:
  void tick();  // one output period
  void handle_commands();
  link::Response execute(const link::Command& c);
  void send_sample(uint64_t seq, float x, float y, uint8_t status);
  void send(const link::CanFrame& f);
  bool silent() const;

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
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

}  // namespace rig::plant
