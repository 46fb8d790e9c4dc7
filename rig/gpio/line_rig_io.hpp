// rig::RigIo over a small line driver. The safety logic lives here, once, for
// every backend: an e-stop edge switches DUT power off FIRST (on the event
// thread, microseconds after the edge), then calls the rig's handler; power
// cannot be switched on while the e-stop is active.
// Drivers: GpiodLines (libgpiod 1.6, gpiod_lines.hpp) and SimLines (memory: host
// tests, where this machine's kernel has no GPIO character device, and the emulated plant).
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "rig/core/gpio.hpp"

namespace rig::gpio {

enum class Output { Power, LampReady, LampRunning, LampPass, LampFail };
inline constexpr int kOutputs = 5;

class LineDriver {
 public:
  virtual ~LineDriver() = default;
  virtual bool has(Output o) const = 0;              // lamps are optional
  virtual void set(Output o, bool active) = 0;       // logical level (active-low handled by the driver)
  virtual bool estop_active() = 0;                   // current logical level of the e-stop input
  // Waits up to `timeout` for an edge on the e-stop input; returns the new
  // logical level, or nullopt on timeout.
  virtual std::optional<bool> wait_estop_edge(std::chrono::milliseconds timeout) = 0;
  // Ends a wait_estop_edge in progress, and every later one, at once with nullopt: the rig is
  // leaving and its watcher must not sleep out its timeout first. A driver without it leaves
  // the watcher to notice at the timeout.
  virtual void wake() {}
  // When the last edge happened, on std::chrono::steady_clock (CLOCK_MONOTONIC):
  // the kernel's event timestamp for libgpiod; nullopt when unknown.
  virtual std::optional<std::chrono::steady_clock::time_point> last_edge_time() const { return std::nullopt; }
  virtual std::string describe() const = 0;
};

class LineRigIo final : public RigIo {
 public:
  explicit LineRigIo(std::unique_ptr<LineDriver> driver);
  ~LineRigIo() override;
  LineRigIo(const LineRigIo&) = delete;
  LineRigIo& operator=(const LineRigIo&) = delete;

  // Switching power on while the e-stop is active throws HardwareError.
  void set_dut_power(bool on) override;
  bool dut_power() const override { return power_; }
  bool estop_active() const override { return estop_; }
  void set_lamp(Lamp lamp, bool on) override;
  void on_estop(std::function<void()> handler) override;
  std::string describe() const override;

  // Time from the last e-stop edge to DUT power being off, seconds: from the
  // kernel's timestamp of the edge when the driver has one, else from the
  // moment the event thread saw it.
  double last_estop_reaction_s() const { return reaction_s_; }

 private:
  void watch();  // the event thread

  std::unique_ptr<LineDriver> drv_;
  std::mutex drv_mu_;  // driver writes from the rig thread and the event thread
  std::atomic<bool> power_{false}, estop_{false}, stop_{false};
  std::atomic<double> reaction_s_{0};
  std::atomic<bool> realtime_{false};  // the watcher runs SCHED_FIFO
  std::mutex handler_mu_;
  std::function<void()> handler_;
  std::thread thread_;
};

// In-memory lines for host tests and the emulated plant. Keeps a log of what happened in
// order ("power=1", "estop=1", ...), so a test can check power went off before the
// handler ran.
class SimLines final : public LineDriver {
 public:
  explicit SimLines(bool with_lamps = true) : with_lamps_(with_lamps) {}
  bool has(Output o) const override { return o == Output::Power || with_lamps_; }
  void set(Output o, bool active) override;
  bool estop_active() override;
  std::optional<bool> wait_estop_edge(std::chrono::milliseconds timeout) override;
  void wake() override;
  std::string describe() const override { return "simulated lines"; }

  // The "hardware" side.
  void drive_estop(bool active);
  // drive_estop, then waits until the line's reader (LineRigIo's watcher) has taken the
  // edge and come back for the next one: power is off and the rig's handler has returned.
  // The lockstep world calls this so an e-stop lands in the same simulated instant every
  // run. A reader that does not come back within 10 s => HardwareError.
  void drive_estop_handled(bool active);
  bool level(Output o) const;
  void note(const std::string& what);
  std::vector<std::string> log() const;

 private:
  bool push_edge_locked(bool active);  // records an edge to `active` (mu_ held); false if none

  bool with_lamps_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool out_[kOutputs]{};
  bool estop_ = false;
  bool woken_ = false;       // wake(): waits return at once
  std::vector<bool> edges_;  // pending edges (new levels)
  std::condition_variable handled_cv_;
  uint64_t taken_ = 0;           // edges the reader has taken
  uint64_t waits_ = 0;           // times the reader has entered wait_estop_edge
  uint64_t waits_at_take_ = 0;   // waits_ when it took the last edge
  std::vector<std::string> log_;
};

}  // namespace rig::gpio
