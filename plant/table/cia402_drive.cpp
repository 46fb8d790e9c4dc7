#include "plant/table/cia402_drive.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace rig::plant {

namespace m = rig::modbus;
namespace c4 = rig::modbus::cia402;
namespace reg = rig::modbus::reg;
namespace ctl = rig::modbus::ctl;
namespace alarm = rig::modbus::alarm;
namespace exc = rig::modbus::exc;
using State = c4::State;
using rig::modbus::Obj;

namespace {

// 0x603F codes the emulated drive reports for the motion model's alarms
// (CiA 301 emergency error code classes: 0x86xx position control, 0x81xx communication).
uint16_t error_code_for(uint16_t alarm_code, uint16_t injected, uint16_t configured) {
  switch (alarm_code) {
    case alarm::kFollowing: return 0x8611;
    case alarm::kOverTravelPos:
    case alarm::kOverTravelNeg: return 0x8612;
    case alarm::kDriveFault: return injected ? injected : configured;
    case alarm::kEstop: return 0xFF01;
    case alarm::kInterlock: return 0x5441;
    case alarm::kHomingFailed: return 0x8A00;
    case alarm::kCommLost: return 0x8130;
    default: return 0x1000;  // generic error
  }
}

}  // namespace

Cia402Drive::Cia402Drive(TableEmulator& axis, m::DriveMap map) : axis_(axis), map_(std::move(map)) {
  const auto& p = axis_.params();
  profile_velocity_ = std::llround(map_.dps_to_velocity_units(p.velocity_dps));
  profile_accel_ = profile_decel_ = std::llround(map_.dps2_to_accel_units(p.accel_dps2));
  quick_stop_decel_ = std::llround(map_.dps2_to_accel_units(p.quick_stop_dps2));
  mode_ = 0;
  target_ = map_.deg_to_counts(axis_.snapshot().position_deg);
  answer_delay_s_ = p.answer_delay_s;
}

double Cia402Drive::home_offset_deg() const { return map_.counts_to_deg(home_offset_); }

void Cia402Drive::axis_control(uint16_t word) {
  axis_control_ = word;
  axis_.write_registers(reg::kControl, &word, 1);
}

// ---------------------------------------------------------------- time

void Cia402Drive::step(double dt_s) {
  axis_.step(dt_s);
  std::lock_guard lk(mu_);
  t_ += dt_s;
  if (state_ == State::kNotReadyToSwitchOn && t_ >= kPowerOnS) enter(State::kSwitchOnDisabled);  // transition 1
  check_axis_fault();
  if (state_ == State::kFaultReactionActive && t_ >= fault_reaction_until_) enter(State::kFault);  // transition 14
  if (setpoint_pending_ && t_ >= setpoint_at_) start_setpoint();
  // A halted positioning continues once its halt ramp has ended, unless a set-point to be
  // changed immediately is about to be taken (or refused) in its place.
  if (resume_pending_ && !axis_.snapshot().moving && !(setpoint_pending_ && (controlword_ & c4::cw::kChangeImmediately)))
    resume();
  if (homing_active_ && homing_pending_) {
    if (!axis_.snapshot().moving) start_axis_homing();
  } else if (homing_active_) {
    const auto s = axis_.snapshot();
    if (!s.homing && !s.moving) {
      homing_active_ = false;
      homing_attained_ = s.homed;
      homing_error_ = !s.homed;
      if (s.homed) target_ = map_.deg_to_counts(inner_to_user_deg(s.position_deg));
    }
  }
}

// A motion-model alarm is a drive fault: Fault reaction active (the brake
// has already caught the axis), then Fault (transitions 13, 14).
void Cia402Drive::check_axis_fault() {
  if (state_ == State::kFault || state_ == State::kFaultReactionActive) return;
  const auto s = axis_.snapshot();
  if (s.alarm_code == alarm::kNone) return;
  if (m::alarm_safe_to_reset(s.alarm_code)) {  // a refusal of the model's own map; never reached via this drive
    axis_control(static_cast<uint16_t>(axis_control_ & ctl::kServoOn));
    axis_control(static_cast<uint16_t>((axis_control_ & ctl::kServoOn) | ctl::kAlarmReset));
    axis_control(static_cast<uint16_t>(axis_control_ & ctl::kServoOn));
    return;
  }
  error_code_ = error_code_for(s.alarm_code, injected_code_, axis_.params().drive_fault_code);
  limit_active_ = s.alarm_code == alarm::kOverTravelPos || s.alarm_code == alarm::kOverTravelNeg;
  homing_active_ = false;
  if (s.alarm_code == alarm::kHomingFailed) homing_error_ = true;
  setpoint_pending_ = false;
  moving_to_target_ = resume_pending_ = false;
  enter(State::kFaultReactionActive);
  fault_reaction_until_ = t_ + 0.01;
}

void Cia402Drive::enter(State s) {
  const bool was_enabled = state_ == State::kOperationEnabled || state_ == State::kQuickStopActive;
  const bool enabled = s == State::kOperationEnabled || s == State::kQuickStopActive;
  if (was_enabled && !enabled && s != State::kFaultReactionActive) {
    axis_control(0);  // power stage off, brake on
    setpoint_pending_ = false;
    moving_to_target_ = resume_pending_ = false;  // enabled again, the drive holds where it is
    homing_active_ = false;
  }
  state_ = s;
}

// ---------------------------------------------------------------- commands

// Device control (IEC 61800-7-201, "Device control commands" and "State
// machine"): a command with no transition from the current state is ignored,
// the state stays; only the listed transitions exist.
void Cia402Drive::apply_controlword(uint16_t w) {
  const uint16_t rising = static_cast<uint16_t>(w & ~controlword_);
  const uint16_t prev = controlword_;
  controlword_ = w;
  if (state_ == State::kFault) {
    if (rising & c4::cw::kFaultReset) {  // transition 15, if the cause is gone
      axis_control(0);
      axis_control(ctl::kAlarmReset);  // the motion model's alarm reset edge
      axis_control(0);
      if (axis_.snapshot().alarm_code == alarm::kNone) {
        error_code_ = 0;
        injected_code_ = 0;
        limit_active_ = false;
        state_ = State::kSwitchOnDisabled;
      }
    }
    return;
  }
  if (state_ == State::kFaultReactionActive || state_ == State::kNotReadyToSwitchOn) return;
  if (w & c4::cw::kFaultReset) return;  // bit 7 set: no device command (the standard's "0xxx" column)
  const bool ev = w & c4::cw::kEnableVoltage, qs = w & c4::cw::kQuickStop, so = w & c4::cw::kSwitchOn,
             eo = w & c4::cw::kEnableOperation;
  const State s = state_;
  if (!ev) {  // Disable voltage: transitions 7, 9, 10, 12
    if (s != State::kSwitchOnDisabled) enter(State::kSwitchOnDisabled);
  } else if (!qs) {  // Quick stop: 7, 10 (to Switch on disabled), 11 (to Quick stop active)
    if (s == State::kReadyToSwitchOn || s == State::kSwitchedOn) {
      enter(State::kSwitchOnDisabled);
    } else if (s == State::kOperationEnabled) {
      // Quick stop option code 6 (0x605A): stop on the quick-stop ramp and stay in Quick stop active.
      axis_control(static_cast<uint16_t>(ctl::kServoOn | ctl::kQuickStop));
      setpoint_pending_ = false;
      moving_to_target_ = resume_pending_ = false;
      homing_active_ = false;
      state_ = State::kQuickStopActive;
    }
  } else if (!so) {  // Shutdown: 2, 6, 8
    if (s == State::kSwitchOnDisabled || s == State::kSwitchedOn || s == State::kOperationEnabled)
      enter(State::kReadyToSwitchOn);
  } else if (!eo) {  // Switch on: 3; Disable operation: 5
    if (s == State::kReadyToSwitchOn || s == State::kOperationEnabled) enter(State::kSwitchedOn);
  } else {  // Enable operation: 4, 16; "Switch on + enable operation" from Ready: 3 + 4
    if (s == State::kSwitchedOn || s == State::kReadyToSwitchOn || s == State::kQuickStopActive) {
      if (s == State::kQuickStopActive) {
        axis_control(ctl::kServoOn);  // drop the quick stop, keep the servo
      } else {
        axis_control(0);
        axis_control(ctl::kServoOn);
      }
      if (axis_.snapshot().servo_on) {
        state_ = State::kOperationEnabled;
      } else {
        state_ = s == State::kQuickStopActive ? s : State::kSwitchedOn;  // power stage refused (e-stop)
      }
    }
  }
  if (state_ != State::kOperationEnabled) return;
  // Operation mode specific bits, only in Operation enabled.
  const bool halt = w & c4::cw::kHalt;
  if (halt && !(prev & c4::cw::kHalt)) {
    axis_control(static_cast<uint16_t>(ctl::kServoOn | ctl::kHalt));
    homing_active_ = false;
    setpoint_pending_ = resume_pending_ = false;
  } else if (!halt && (prev & c4::cw::kHalt)) {
    axis_control(ctl::kServoOn);
    // Profile position, halt = 0: "positioning shall be executed or continued" (IEC 61800-7-201):
    // a positioning the halt interrupted goes on to its target, unless a new set-point to be
    // changed immediately is taken in its place (one this very word brings; one refused, outside
    // the limits, leaves the old one to continue). Homing interrupted by a halt is not resumed:
    // bits 13, 12, 10 say "interrupted", and a new homing start is needed.
    const bool short_of_target = std::fabs(axis_.snapshot().position_deg - target_inner_deg_) >
                                 axis_.params().in_position_window_deg;
    resume_pending_ = mode_ == c4::kModeProfilePosition && moving_to_target_ && short_of_target;
  }
  // Homing mode, bit 4 from 1 to 0 while the homing runs: "interrupt homing mode" (IEC 61800-7-201,
  // homing mode controlword): the axis stops on its ramp without the home, and bits 13, 12, 10 say
  // "interrupted" once it is at rest. It homed on regardless (a review).
  if (mode_ == c4::kModeHoming && homing_active_ && (prev & ~w & c4::cw::kHomingStart)) {
    axis_control(static_cast<uint16_t>(ctl::kServoOn | ctl::kHalt));
    axis_control(ctl::kServoOn);
    homing_active_ = false;
  }
  if (!(w & c4::cw::kNewSetPoint)) setpoint_ack_ = false;  // handshake: the master took the acknowledge
  if (!(rising & c4::cw::kNewSetPoint) || halt) return;
  if (mode_ == c4::kModeHoming) {
    // Methods 1..37 home on the switch at mechanical 0 in this model; others are a homing error.
    if (homing_method_ < 1 || homing_method_ > 37) {
      homing_error_ = true;
      return;
    }
    homing_error_ = homing_attained_ = false;
    homing_active_ = true;
    homing_pending_ = axis_.snapshot().moving;
    if (!homing_pending_) start_axis_homing();
  } else if (mode_ == c4::kModeProfilePosition) {
    if (setpoint_ack_ || setpoint_pending_) return;  // previous set-point not yet taken by the master
    setpoint_pending_ = true;
    setpoint_at_ = t_ + setpoint_latency_s_;
  }
}

void Cia402Drive::start_axis_homing() {
  homing_pending_ = false;
  axis_control(ctl::kServoOn);
  axis_control(static_cast<uint16_t>(ctl::kServoOn | ctl::kHome));
  axis_control(ctl::kServoOn);
}

// Continues the positioning a released halt interrupted, to the target it had.
void Cia402Drive::resume() {
  resume_pending_ = false;
  axis_control(static_cast<uint16_t>(ctl::kServoOn | ctl::kStart));
  axis_control(ctl::kServoOn);
}

// Takes the set-point (single set-point mode): a move under way is replaced
// only with "change set immediately"; otherwise the set-point waits for it.
void Cia402Drive::start_setpoint() {
  const auto s = axis_.snapshot();
  // Single set-point: a positioning under way, or one a released halt is to continue, is
  // completed first unless the set-point is to be changed immediately.
  if ((s.moving || resume_pending_) && !(controlword_ & c4::cw::kChangeImmediately)) return;
  setpoint_pending_ = false;
  double user = map_.counts_to_deg(target_);
  if (controlword_ & c4::cw::kRelative) user += inner_to_user_deg(target_inner_deg_);  // relative to the last target
  if (user < map_.limit_neg_deg || user > map_.limit_pos_deg || !s.homed) {
    // Outside the software limits (0x607D) or without a reference: not taken.
    limit_active_ = user < map_.limit_neg_deg || user > map_.limit_pos_deg;
    warning_ = true;
    return;
  }
  resume_pending_ = false;  // taken in place of the positioning a halt interrupted
  warning_ = limit_active_ = false;
  target_inner_deg_ = user_to_inner_deg(user);
  uint16_t w[2];
  m::split_i32(static_cast<int32_t>(std::lround(target_inner_deg_ * m::kPosScale)), w);
  axis_.write_registers(reg::kTargetPos, w, 2);
  const double v = std::fabs(map_.velocity_units_to_dps(static_cast<double>(profile_velocity_)));
  const double a = map_.accel_units_to_dps2(static_cast<double>(profile_accel_));
  if (v > 0) {
    m::split_u32(static_cast<uint32_t>(std::lround(std::min(v, axis_.params().max_velocity_dps) * m::kVelScale)), w);
    axis_.write_registers(reg::kVelocity, w, 2);
  }
  if (a > 0) {
    m::split_u32(static_cast<uint32_t>(std::lround(std::min(a, axis_.params().max_accel_dps2) * m::kVelScale)), w);
    axis_.write_registers(reg::kAccel, w, 2);
  }
  axis_control(ctl::kServoOn);
  axis_control(static_cast<uint16_t>(ctl::kServoOn | ctl::kStart));
  axis_control(ctl::kServoOn);
  // Acknowledged while the master still holds bit 4; a master that cleared it before the drive
  // took the set-point has ended the handshake: an acknowledge set then stayed set, and the next
  // set-point was refused as not yet taken (a review).
  setpoint_ack_ = (controlword_ & c4::cw::kNewSetPoint) != 0;
  moving_to_target_ = true;
}

// ---------------------------------------------------------------- status

uint16_t Cia402Drive::statusword_locked() const {
  uint16_t s = c4::state_bits(state_) | c4::sw::kRemote;
  if (warning_) s |= c4::sw::kWarning;
  if (limit_active_) s |= c4::sw::kInternalLimit;
  const auto a = axis_.snapshot();
  const bool halted = controlword_ & c4::cw::kHalt;
  const bool at_rest = a.in_position && !a.moving;
  if (mode_ == c4::kModeHoming) {
    // Bits 13, 12, 10: in progress 0,0,0; interrupted / not started 0,0,1;
    // attained 0,1,1 (not 0,1,0 while the axis settles); error 1,x,x.
    if (!homing_active_ && at_rest) s |= c4::sw::kTargetReached;
    if (homing_attained_) s |= c4::sw::kHomingAttained;
    if (homing_error_) s |= c4::sw::kHomingError;
  } else if (mode_ == c4::kModeProfilePosition) {
    if (setpoint_ack_) s |= c4::sw::kSetPointAck;
    // Target reached: at rest within the window of the target; with halt set,
    // at rest anywhere (the axis has zero velocity).
    const bool near = std::fabs(a.position_deg - target_inner_deg_) <= axis_.params().in_position_window_deg;
    if (at_rest && !setpoint_pending_ && (halted || near || !moving_to_target_)) s |= c4::sw::kTargetReached;
    if (error_code_ == 0x8611) s |= c4::sw::kFollowingError;
  }
  if (map_.homed_bit && a.homed) s |= static_cast<uint16_t>(1u << *map_.homed_bit);
  return s;
}

int64_t Cia402Drive::value_of(Obj o) const {
  const auto a = axis_.snapshot();
  switch (o) {
    case Obj::kControlword: return controlword_;
    case Obj::kStatusword: return statusword_locked();
    case Obj::kErrorCode: return error_code_;
    case Obj::kModesOfOperation:
    case Obj::kModesDisplay: return mode_;
    case Obj::kPositionActual: return map_.deg_to_counts(a.homed ? inner_to_user_deg(a.position_deg) : a.position_deg);
    case Obj::kVelocityActual: {
      // The map's conversion (its units and resolution), signed as the axis turns.
      const double units = std::copysign(map_.dps_to_velocity_units(a.velocity_dps), a.velocity_dps);
      return std::llround(units * map_.direction);
    }
    case Obj::kTargetPosition: return target_;
    case Obj::kProfileVelocity: return profile_velocity_;
    case Obj::kProfileAcceleration: return profile_accel_;
    case Obj::kProfileDeceleration: return profile_decel_;
    case Obj::kQuickStopDeceleration: return quick_stop_decel_;
    case Obj::kHomingMethod: return homing_method_;
    case Obj::kHomeOffset: return home_offset_;
    case Obj::kFollowingErrorActual: return map_.deg_to_counts(a.reference_deg - a.position_deg);
    // A servo drive of profile 402; a 16-bit mapping holds the profile number alone.
    case Obj::kDeviceType: return map_.spec(o).width == 16 ? c4::kDeviceProfile : c4::kDeviceTypeServo;
    case Obj::kCount: break;
  }
  return 0;
}

void Cia402Drive::set_value(Obj o, int64_t v) {
  switch (o) {
    case Obj::kModesOfOperation:
      // Another mode ends a positioning the halt had interrupted: nothing to continue.
      if (static_cast<int8_t>(v) != mode_) moving_to_target_ = resume_pending_ = false;
      mode_ = static_cast<int8_t>(v);
      break;
    case Obj::kTargetPosition: target_ = v; break;
    case Obj::kProfileVelocity: profile_velocity_ = v; break;
    case Obj::kProfileAcceleration: profile_accel_ = v; break;
    case Obj::kProfileDeceleration: profile_decel_ = v; break;
    case Obj::kQuickStopDeceleration: quick_stop_decel_ = v; break;
    case Obj::kHomingMethod: homing_method_ = v; break;
    case Obj::kHomeOffset: home_offset_ = v; break;
    default: break;
  }
}

// ---------------------------------------------------------------- registers

uint8_t Cia402Drive::read_space(bool input, uint16_t addr, uint16_t n, uint16_t* out) {
  std::lock_guard lk(mu_);
  if (n < 1 || n > 125) return exc::kIllegalValue;
  for (uint32_t a = addr; a < static_cast<uint32_t>(addr) + n;) {
    bool found = false;
    for (int i = 0; i < m::kObjCount && !found; ++i) {
      const auto o = static_cast<Obj>(i);
      const m::ObjectSpec& s = map_.spec(o);
      if (!s.present || s.input != input || a < s.address || a >= s.address + static_cast<uint32_t>(s.words())) continue;
      const auto words = map_.encode(o, value_of(o));
      for (uint32_t k = a - s.address; k < words.size() && a < static_cast<uint32_t>(addr) + n; ++k, ++a)
        out[a - addr] = words[k];
      found = true;
    }
    if (!found) return exc::kIllegalAddress;  // a register no object of the map covers
  }
  return exc::kNone;
}

uint8_t Cia402Drive::read_registers(uint16_t addr, uint16_t n, uint16_t* out) { return read_space(false, addr, n, out); }
uint8_t Cia402Drive::read_input_registers(uint16_t addr, uint16_t n, uint16_t* out) {
  return read_space(true, addr, n, out);
}

// Validates the whole request (every register writable, 32-bit objects whole),
// then applies the values with the controlword last, so a target and its
// new-set-point edge may go in one request.
uint8_t Cia402Drive::write_registers(uint16_t addr, const uint16_t* v, uint16_t n) {
  std::lock_guard lk(mu_);
  if (n < 1 || n > 123) return exc::kIllegalValue;
  const uint32_t end = static_cast<uint32_t>(addr) + n;
  std::vector<std::pair<Obj, int64_t>> writes;
  for (uint32_t a = addr; a < end;) {
    bool found = false;
    for (int i = 0; i < m::kObjCount && !found; ++i) {
      const auto o = static_cast<Obj>(i);
      const m::ObjectSpec& s = map_.spec(o);
      if (!s.present || s.input || a < s.address || a >= s.address + static_cast<uint32_t>(s.words())) continue;
      if (!m::object_info(o).writable || a != s.address || a + s.words() > end) return exc::kIllegalAddress;
      writes.emplace_back(o, map_.decode(o, v + (a - addr)));
      a += s.words();
      found = true;
    }
    if (!found) return exc::kIllegalAddress;
  }
  for (const auto& [o, val] : writes) {
    if ((o == Obj::kModesOfOperation) && val != c4::kModeProfilePosition && val != c4::kModeHoming && val != 0)
      return exc::kIllegalValue;  // modes this drive does not implement
    if ((o == Obj::kProfileVelocity || o == Obj::kProfileAcceleration || o == Obj::kProfileDeceleration ||
         o == Obj::kQuickStopDeceleration) && val <= 0)
      return exc::kIllegalValue;
  }
  std::optional<int64_t> control;
  for (const auto& [o, val] : writes) {
    if (o == Obj::kControlword) {
      control = val;
    } else {
      set_value(o, val);
    }
  }
  if (control) apply_controlword(static_cast<uint16_t>(*control));
  return exc::kNone;
}

bool Cia402Drive::answering() const { return axis_.answering(); }

double Cia402Drive::answer_delay_s() const {
  std::lock_guard lk(mu_);
  return answer_delay_s_;
}

void Cia402Drive::set_setpoint_latency(double s) {
  std::lock_guard lk(mu_);
  setpoint_latency_s_ = s;
}

bool Cia402Drive::setpoint_pending() const {
  std::lock_guard lk(mu_);
  return setpoint_pending_;
}

void Cia402Drive::set_answer_delay(double s) {
  std::lock_guard lk(mu_);
  answer_delay_s_ = s;
}

void Cia402Drive::inject_drive_fault(uint16_t error_code) {
  {
    std::lock_guard lk(mu_);
    injected_code_ = error_code;
  }
  axis_.inject(SimFault::kDriveFault);
  std::lock_guard lk(mu_);
  check_axis_fault();
}

State Cia402Drive::state() const {
  std::lock_guard lk(mu_);
  return state_;
}
uint16_t Cia402Drive::statusword() const {
  std::lock_guard lk(mu_);
  return statusword_locked();
}
uint16_t Cia402Drive::error_code() const {
  std::lock_guard lk(mu_);
  return error_code_;
}

}  // namespace rig::plant
