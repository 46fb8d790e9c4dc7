// The emulated CiA 402 servo drive: the CiA 402 power drive state machine,
// profile position and homing modes (IEC 61800-7-201) served on the registers
// a drive map (rig/modbus/drive_map.hpp) names, over the same motion model as
// the rig-v1 emulated table (TableEmulator is its power stage and mechanics).
// Thread-safe like TableEmulator: the Modbus server thread and the plant share it.
#pragma once
#include <cstdint>
#include <mutex>
#include <optional>

#include "plant/table/table_emulator.hpp"
#include "rig/modbus/cia402.hpp"
#include "rig/modbus/drive_map.hpp"

namespace rig::plant {

class Cia402Drive final : public rig::modbus::RegisterDevice {
 public:
  // `axis` is the motion model (its rig-v1 registers are the drive's inside;
  // never served). Its travel limits should be the map's.
  Cia402Drive(TableEmulator& axis, rig::modbus::DriveMap map);

  // Advances the axis and the drive's own timers (power-on, set-point
  // latency, fault reaction).
  void step(double dt_s);

  uint8_t read_registers(uint16_t addr, uint16_t n, uint16_t* out) override;
  uint8_t read_input_registers(uint16_t addr, uint16_t n, uint16_t* out) override;
  uint8_t write_registers(uint16_t addr, const uint16_t* values, uint16_t n) override;
  bool answering() const override;
  double answer_delay_s() const override;

  // Fault injection: a power-stage fault with this 0x603F code, now; slow answers.
  void inject_drive_fault(uint16_t error_code);
  void set_answer_delay(double s);
  // A slow drive cycle: new set-points are acknowledged this long after their edge (default
  // kSetPointLatencyS); and whether one is waiting for it.
  void set_setpoint_latency(double s);
  bool setpoint_pending() const;

  rig::modbus::cia402::State state() const;
  uint16_t statusword() const;
  uint16_t error_code() const;
  const rig::modbus::DriveMap& map() const { return map_; }
  TableEmulator& axis() { return axis_; }

  // Drive cycle: a new set-point is acknowledged this long after its edge.
  static constexpr double kSetPointLatencyS = 0.002;
  // Power-on: Not ready to switch on for this long, then Switch on disabled.
  static constexpr double kPowerOnS = 0.02;

 private:
  using State = rig::modbus::cia402::State;
  using Obj = rig::modbus::Obj;
  void axis_control(uint16_t word);  // writes the axis's rig-v1 control word
  void apply_controlword(uint16_t w);
  void enter(State s);
  void start_setpoint();
  void check_axis_fault();
  void resume();
  uint16_t statusword_locked() const;
  int64_t value_of(Obj o) const;
  void set_value(Obj o, int64_t v);
  uint8_t read_space(bool input, uint16_t addr, uint16_t n, uint16_t* out);
  // After homing the home switch (model coordinate 0) reads as the home offset.
  double inner_to_user_deg(double inner) const { return inner + home_offset_deg(); }
  double user_to_inner_deg(double user) const { return user - home_offset_deg(); }
  double home_offset_deg() const;

  TableEmulator& axis_;
  rig::modbus::DriveMap map_;
  mutable std::mutex mu_;
  State state_ = State::kNotReadyToSwitchOn;
  double t_ = 0, fault_reaction_until_ = -1, setpoint_at_ = -1;
  uint16_t controlword_ = 0, axis_control_ = 0, error_code_ = 0;
  int8_t mode_ = 0;
  int64_t target_ = 0, profile_velocity_ = 0, profile_accel_ = 0, profile_decel_ = 0, quick_stop_decel_ = 0;
  int64_t homing_method_ = 19, home_offset_ = 0;  // the drive's own homing method until one is written
  bool setpoint_ack_ = false, setpoint_pending_ = false, moving_to_target_ = false;
  // A positioning interrupted by halt and to be continued once the halt ramp has ended (halt
  // released: "positioning shall be executed or continued", IEC 61800-7-201 profile position).
  bool resume_pending_ = false;
  bool homing_active_ = false, homing_attained_ = false, homing_error_ = false;
  // A homing start taken while the axis still runs down a ramp (an interrupted homing, a halted
  // move): the homing starts once it is at rest (the axis refuses a start mid-ramp as busy).
  bool homing_pending_ = false;
  void start_axis_homing();
  bool limit_active_ = false, warning_ = false;
  double target_inner_deg_ = 0;
  double answer_delay_s_ = 0;
  double setpoint_latency_s_ = kSetPointLatencyS;
  uint16_t injected_code_ = 0;
};

}  // namespace rig::plant
