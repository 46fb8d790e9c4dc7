// The emulated rotary table: a positioning drive's register map
// (docs/table-registers.md) over a motion model: trapezoidal profile, a
// second-order servo loop with velocity feed-forward (settling, following
// error), per-move repeatability error of the mechanics, homing, travel limits,
// e-stop/interlock inputs and injectable faults. Advanced by step(dt); every
// public member is thread-safe (the Modbus server thread and the plant share it).
#pragma once
#include <bit>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>

#include <toml++/toml.h>

#include "rig/core/table.hpp"
#include "rig/modbus/registers.hpp"

namespace rig::plant {

using rig::modbus::SimFault;

struct TableParams {
  double velocity_dps = rig::table_defaults::kVelocityDps;  // profile velocity at power-on
  double accel_dps2 = rig::table_defaults::kAccelDps2;      // profile acceleration = deceleration
  double home_velocity_dps = 20.0;
  double quick_stop_dps2 = 600.0;        // quick-stop ramp
  double max_velocity_dps = 360.0;       // writes above are refused (exception 03)
  double max_accel_dps2 = 3600.0;
  double in_position_window_deg = 0.001;
  double settle_s = rig::table_defaults::kDriveSettleS;     // drive's in-position settle time
  double servo_bandwidth_hz = 8.0;       // natural frequency of the position loop
  double damping = 0.8;
  double following_error_limit_deg = 2.0;
  double repeatability_deg = 0.0005;     // 1 sigma of the mechanical angle per move (invisible to the encoder)
  double limit_neg_deg = -190.0;         // soft travel limits (drive coordinates after homing)
  double limit_pos_deg = 370.0;
  double start_angle_deg = -1.0;         // mechanical angle at power-on; < 0 = random in [0, 360) from the seed
  bool homed_at_start = false;
  double comm_timeout_s = 0.0;           // > 0: no request for this long while moving = alarm 0x0070
  SimFault fault = SimFault::kNone;      // injected on move number fault_on_move (1-based) ...
  int fault_on_move = 1;
  double fault_at = 0.5;                 // ... at this fraction of its profile time
  uint16_t drive_fault_code = 0x2310;    // 0x603F the emulated CiA 402 drive reports for drive_fault
  double answer_delay_s = 0.0;           // slow answers: every reply waits this long
};

// Reads [plant.table] (may be null = defaults); unknown keys and bad values
// are ConfigErrors naming file:line.
TableParams table_params_from_toml(const toml::table* cfg);
SimFault parse_sim_fault(const std::string& name);  // "none|over_travel|following_error|drive_fault|no_answer"

class TableEmulator final : public rig::modbus::RegisterDevice {
 public:
  TableEmulator(const TableParams& p, uint64_t seed);

  // Advances the world by dt seconds (internally in <= 0.5 ms steps).
  void step(double dt_s);
  // True mechanical angle of the table (what the DUT feels), degrees.
  double actual_angle_deg() const;
  double time_s() const;

  // RegisterDevice (the Modbus side).
  uint8_t read_registers(uint16_t addr, uint16_t n, uint16_t* out) override;
  uint8_t write_registers(uint16_t addr, const uint16_t* values, uint16_t n) override;
  bool answering() const override;
  double answer_delay_s() const override { return p_.answer_delay_s; }

  // Fault injection. `at_fraction` <= 0: now; otherwise when the next move
  // reaches that fraction of its profile time.
  void inject(SimFault f, double at_fraction = 0.0);
  void clear_no_answer();
  void set_estop(bool pressed);
  void set_interlock(bool closed);

  struct Snapshot {
    double position_deg, velocity_dps, reference_deg, mechanical_deg;
    uint16_t status, alarm_code, move_seq;
    bool servo_on, homed, homing, moving, in_position;
    int moves_started;
  };
  Snapshot snapshot() const;
  const TableParams& params() const { return p_; }

 private:
  // A piecewise constant-acceleration reference from (r0, v0) at t0.
  struct Trajectory {
    bool active = false;
    double t0 = 0, r0 = 0, v0 = 0, end = 0, total = 0;
    double dur[3] = {0, 0, 0}, acc[3] = {0, 0, 0};
    bool is_move = false;  // a START move (fault injection counts these)
    double stop_decel = 0;  // a stop's ramp (deg/s^2); 0 for a move or a homing run
    void eval(double tau, double& r, double& v) const;
  };

  void substep(double h);
  void plan_move(double target, double vmax, double amax, bool is_move);
  void plan_stop(double decel);
  void raise(uint16_t code);
  void fire(SimFault f);
  void finish_homing();
  uint8_t apply_control(uint16_t word);
  uint16_t status_word() const;
  bool in_position() const;
  bool in_window() const;
  bool moving() const;
  void image(uint16_t* drive, uint16_t* sim) const;

  // The servo update's inputs (reference, its velocity, position, velocity, substep).
  struct ServoInput {
    double ref, ref_v, pos, vel, h;
    bool same_bits(const ServoInput& o) const {
      return std::bit_cast<uint64_t>(ref) == std::bit_cast<uint64_t>(o.ref) &&
             std::bit_cast<uint64_t>(ref_v) == std::bit_cast<uint64_t>(o.ref_v) &&
             std::bit_cast<uint64_t>(pos) == std::bit_cast<uint64_t>(o.pos) &&
             std::bit_cast<uint64_t>(vel) == std::bit_cast<uint64_t>(o.vel) &&
             std::bit_cast<uint64_t>(h) == std::bit_cast<uint64_t>(o.h);
    }
  };

  TableParams p_;
  mutable std::mutex mu_;
  std::mt19937_64 rng_;
  double t_ = 0, hb_acc_ = 0;
  uint32_t heartbeat_ = 0;
  // Axis: drive coordinates (encoder); mechanical = pos_ + mech_offset_ + rep_err_.
  double pos_ = 0, vel_ = 0, mech_offset_ = 0, rep_err_ = 0;
  double ref_ = 0, ref_v_ = 0, settle_target_ = 0, in_pos_timer_ = 0;
  bool settling_ = false;
  std::optional<ServoInput> fixed_point_;  // inputs the servo update returned unchanged
  Trajectory traj_;
  bool servo_ = false, homed_ = false, homing_ = false, stuck_ = false;
  uint16_t control_ = 0, alarm_ = 0, move_seq_ = 0;
  int32_t target_counts_ = 0;
  uint32_t vel_counts_, acc_counts_;
  uint16_t window_counts_, settle_ms_;
  // Faults and inputs.
  SimFault armed_ = SimFault::kNone;
  double armed_at_ = 0;
  int armed_move_ = 0;      // 0 = the next move
  bool fault_this_move_ = false;
  bool no_answer_ = false, estop_ = false, interlock_open_ = false;
  int moves_started_ = 0;
  double last_request_t_ = 0;
};

std::unique_ptr<TableEmulator> make_table_emulator(const toml::table* cfg /* [plant.table], may be null */,
                                                   uint64_t seed);

}  // namespace rig::plant
