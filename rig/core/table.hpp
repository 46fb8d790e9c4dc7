// Rotary table seam: a dividing head driven by a positioning servo.
// Real backend: Modbus (rig/modbus). Emulated: the same client logic over the
// emulator's register map in-process (plant/table).
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "rig/core/cancel.hpp"

namespace rig {

struct TableStatus {
  double actual_deg = 0.0;
  double target_deg = 0.0;
  bool ready = false;
  bool servo_on = false;
  bool homed = false;
  // False when the drive cannot say whether it is homed (a CiA 402 map without homed_bit, read
  // by a client that did not home it): `homed` is then false for "not known", not "lost".
  bool homed_known = true;
  bool homing = false;
  bool moving = false;
  bool in_position = false;
  bool alarm = false;
  bool estop = false;
  bool interlock_ok = true;
  uint16_t alarm_code = 0;
  std::string alarm_text;  // meaning of alarm_code, empty when none
  uint32_t heartbeat = 0;
  bool has_heartbeat = true;  // a CiA 402 drive has no heartbeat register (frozen = no change)
  std::string drive_state;    // the drive's own state name where it has one (CiA 402), else empty
  // The over-travel switches where the drive reports them (rig-v1 STATUS bits 8, 9): which one
  // an over-travel alarm stands on says which way to move off it. False where it cannot say.
  bool limit_pos = false, limit_neg = false;
  bool has_limit_switches = false;
};

// Duration of a trapezoidal move of `dist` degrees from rest to rest (peak velocity v, acceleration
// a; triangular when too short to reach v): the clients' time bounds and the procedure's plan.
inline double trapezoid_time(double dist, double v, double a) {
  if (v <= 0 || a <= 0) return 0;
  dist = std::fabs(dist);
  if (dist >= v * v / a) return dist / v + v / a;
  return 2.0 * std::sqrt(dist / a);
}

// The table's timing where nothing sets it, in the one place the three that use it may all
// include (they may not include each other, docs/architecture.md): the Modbus client's own
// (rig::modbus::TableOptions), the emulated drive's power-on profile (rig::plant::TableParams,
// docs/table-registers.md) and the procedure's plan, which costs each move with both
// (rig::acceptance::TableTiming) unless the hardware file or [plant.table] says otherwise.
namespace table_defaults {
inline constexpr double kVelocityDps = 30.0;   // the drive's profile velocity at power-on
inline constexpr double kAccelDps2 = 60.0;     // its profile acceleration = deceleration
inline constexpr double kDriveSettleS = 0.1;   // its in-position settle time
inline constexpr double kClientSettleS = 0.5;  // the client's: in position held this long
inline constexpr double kClientPollS = 0.05;   // the client's status polling period while waiting
}  // namespace table_defaults

// Every call is bounded in time; failures throw HardwareError naming what the
// table was doing; a requested cancel throws AbortedError after a stop command.
class RotaryTable {
 public:
  virtual ~RotaryTable() = default;
  virtual TableStatus status() = 0;
  // Homes the axis and waits until homed (bounded).
  virtual void home(const CancelToken& cancel) = 0;
  // Moves to `deg`, returns once in position for the settle time and the actual
  // angle reads back within tolerance.
  virtual void move_to(double deg, const CancelToken& cancel) = 0;
  // Controlled stop (decelerates). Never throws on a dead link: safe-state path.
  virtual void stop() noexcept = 0;
  // Immediate stop (quick stop / e-stop ramp). Never throws.
  virtual void quick_stop() noexcept = 0;
  virtual std::string describe() const = 0;  // "modbus tcp 127.0.0.1:1502 unit 1"
  // The travel [negative, positive] in degrees as the drive holds it, where the client can tell
  // (a rig-v1 drive's limit registers, a CiA 402 map's [limits]); nullopt where it cannot. The
  // procedure checks its U10/U20 angles against it after homing, before the first recording.
  virtual std::optional<std::pair<double, double>> travel_deg(const CancelToken&) { return std::nullopt; }
  // What became of the last stop or quick stop: "" delivered, else why not (not delivered, not
  // sent into a device that is not the configured drive, none needed). For the safe state's log.
  virtual std::string stop_fate() const { return ""; }

  // Called with the angle read, each time the client reads the drive (while home() and move_to()
  // wait, every poll): `rig table` shows the turning table with it. On the caller's thread;
  // it must not throw or block.
  void on_angle(std::function<void(double actual_deg)> f) { on_angle_ = std::move(f); }

 protected:
  void angle_seen(double deg) const {
    if (on_angle_) on_angle_(deg);
  }

 private:
  std::function<void(double)> on_angle_;
};

}  // namespace rig
