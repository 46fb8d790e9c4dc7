// Rig I/O seam: DUT power, interlock/e-stop input, lamps.
// Real backend: libgpiod 1.6 (rig/gpio). Simulated: SimGpio below.
#pragma once
#include <atomic>
#include <functional>
#include <mutex>
#include <string>

namespace rig {

enum class Lamp { Ready, Running, Pass, Fail };
inline const char* to_string(Lamp l) {
  switch (l) {
    case Lamp::Ready: return "ready";
    case Lamp::Running: return "running";
    case Lamp::Pass: return "pass";
    case Lamp::Fail: return "fail";
  }
  return "?";
}

class RigIo {
 public:
  virtual ~RigIo() = default;
  virtual void set_dut_power(bool on) = 0;  // safe-state path calls this: must not block
  virtual bool dut_power() const = 0;
  virtual bool estop_active() const = 0;    // true while the e-stop/interlock is open
  virtual void set_lamp(Lamp lamp, bool on) = 0;
  // Called from the backend's event thread on an e-stop edge. The backend has
  // already switched DUT power off itself when this fires (hard safety first).
  virtual void on_estop(std::function<void()> handler) = 0;
  virtual std::string describe() const = 0;
};

// In-memory lines for host tests and the emulated plant. trip_estop() behaves
// like the real backend's edge handler: power off first, then the handler.
class SimGpio final : public RigIo {
 public:
  void set_dut_power(bool on) override { power_ = on; }
  bool dut_power() const override { return power_; }
  bool estop_active() const override { return estop_; }
  void set_lamp(Lamp lamp, bool on) override { lamps_[static_cast<int>(lamp)] = on; }
  bool lamp(Lamp lamp) const { return lamps_[static_cast<int>(lamp)]; }
  void on_estop(std::function<void()> handler) override {
    std::lock_guard lk(mu_);
    handler_ = std::move(handler);
  }
  void trip_estop() {
    estop_ = true;
    power_ = false;
    std::function<void()> h;
    {
      std::lock_guard lk(mu_);
      h = handler_;
    }
    if (h) h();
  }
  void release_estop() { estop_ = false; }
  std::string describe() const override { return "simulated gpio"; }

 private:
  std::atomic<bool> power_{false}, estop_{false};
  std::atomic<bool> lamps_[4]{};
  std::mutex mu_;
  std::function<void()> handler_;
};

}  // namespace rig
