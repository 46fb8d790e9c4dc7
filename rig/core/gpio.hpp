// Rig I/O seam: DUT power, interlock/e-stop input, lamps.
// One implementation of the safety logic, rig/gpio LineRigIo, over libgpiod 1.6 lines
// (the rig) or simulated lines (host tests and the emulated plant).
#pragma once
#include <functional>
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

}  // namespace rig
