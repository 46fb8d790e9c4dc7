#include "plant/table/table_emulator.hpp"

#include <algorithm>
#include <cmath>

#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {

namespace m = rig::modbus;
namespace reg = rig::modbus::reg;
namespace ctl = rig::modbus::ctl;
namespace sts = rig::modbus::sts;
namespace alarm = rig::modbus::alarm;
namespace exc = rig::modbus::exc;

namespace {
constexpr double kSubstep = 0.0005;   // s; the servo loop's integration step
constexpr double kHeartbeatPeriod = 0.01;
constexpr double kPi = 3.14159265358979323846;

int32_t to_counts(double deg) { return static_cast<int32_t>(std::lround(deg * m::kPosScale)); }
uint32_t to_vcounts(double v) { return static_cast<uint32_t>(std::lround(v * m::kVelScale)); }
}  // namespace

// ---------------------------------------------------------------- config

SimFault parse_sim_fault(const std::string& name) {
  if (name == "none") return SimFault::kNone;
  if (name == "over_travel") return SimFault::kOverTravel;
  if (name == "following_error") return SimFault::kFollowing;
  if (name == "drive_fault") return SimFault::kDriveFault;
  if (name == "no_answer") return SimFault::kNoAnswer;
  throw ConfigError("unknown table fault '" + name +
                    "' (expected none, over_travel, following_error, drive_fault, no_answer)");
}

TableParams table_params_from_toml(const toml::table* t) {
  TableParams p;
  if (!t) return p;
  cfg::check_keys(*t,
                  {"velocity_dps", "accel_dps2", "home_velocity_dps", "quick_stop_dps2", "max_velocity_dps",
                   "max_accel_dps2", "in_position_window_deg", "settle_s", "servo_bandwidth_hz", "damping",
                   "following_error_limit_deg", "repeatability_deg", "limit_neg_deg", "limit_pos_deg",
                   "start_angle_deg", "homed_at_start", "comm_timeout_s", "fault", "fault_on_move", "fault_at",
                   "drive_fault_code", "answer_delay_s"},
                  "plant.table");
  p.max_velocity_dps = cfg::get_number(*t, "max_velocity_dps", p.max_velocity_dps, 0.01, 4000.0);
  p.max_accel_dps2 = cfg::get_number(*t, "max_accel_dps2", p.max_accel_dps2, 0.01, 40000.0);
  p.velocity_dps = cfg::get_number(*t, "velocity_dps", p.velocity_dps, 0.001, p.max_velocity_dps);
  p.accel_dps2 = cfg::get_number(*t, "accel_dps2", p.accel_dps2, 0.001, p.max_accel_dps2);
  p.home_velocity_dps = cfg::get_number(*t, "home_velocity_dps", p.home_velocity_dps, 0.001, p.max_velocity_dps);
  p.quick_stop_dps2 = cfg::get_number(*t, "quick_stop_dps2", p.quick_stop_dps2, 0.001, 1e6);
  p.in_position_window_deg = cfg::get_number(*t, "in_position_window_deg", p.in_position_window_deg, 0.0001, 6.5);
  // SETTLE_TIME is at most 10000 ms (docs/table-registers.md): a longer one served a map rig's
  // own client then refused as "not a rig-v1 drive" (a review).
  p.settle_s = cfg::get_number(*t, "settle_s", p.settle_s, 0.0, 10.0);
  p.servo_bandwidth_hz = cfg::get_number(*t, "servo_bandwidth_hz", p.servo_bandwidth_hz, 0.1, 100.0);
  p.damping = cfg::get_number(*t, "damping", p.damping, 0.1, 5.0);
  p.following_error_limit_deg = cfg::get_number(*t, "following_error_limit_deg", p.following_error_limit_deg, 0.001, 360.0);
  p.repeatability_deg = cfg::get_number(*t, "repeatability_deg", p.repeatability_deg, 0.0, 1.0);
  p.limit_neg_deg = cfg::get_number(*t, "limit_neg_deg", p.limit_neg_deg, -200000.0, 0.0);
  p.limit_pos_deg = cfg::get_number(*t, "limit_pos_deg", p.limit_pos_deg, 0.0, 200000.0);
  p.start_angle_deg = cfg::get_number(*t, "start_angle_deg", p.start_angle_deg, -1.0, 360.0);
  p.homed_at_start = cfg::get_bool(*t, "homed_at_start", p.homed_at_start);
  p.comm_timeout_s = cfg::get_number(*t, "comm_timeout_s", p.comm_timeout_s, 0.0, 3600.0);
  if (const toml::node* n = t->get("fault")) {
    try {
      p.fault = parse_sim_fault(cfg::get_string(*t, "fault"));
    } catch (const ConfigError& e) {
      throw ConfigError(cfg::where(*n) + ": " + e.what());
    }
  }
  p.fault_on_move = static_cast<int>(cfg::get_int(*t, "fault_on_move", p.fault_on_move, 1, 1000000));
  p.fault_at = cfg::get_number(*t, "fault_at", p.fault_at, 0.001, 1.0);
  p.drive_fault_code = static_cast<uint16_t>(cfg::get_int(*t, "drive_fault_code", p.drive_fault_code, 1, 0xFFFF));
  p.answer_delay_s = cfg::get_number(*t, "answer_delay_s", p.answer_delay_s, 0.0, 10.0);
  return p;
}

// ---------------------------------------------------------------- model

void TableEmulator::Trajectory::eval(double tau, double& r, double& v) const {
  if (tau >= total) {
    r = end;
    v = 0;
    return;
  }
  r = r0;
  v = v0;
  for (int i = 0; i < 3 && tau > 0; ++i) {
    const double dt = std::min(tau, dur[i]);
    r += v * dt + 0.5 * acc[i] * dt * dt;
    v += acc[i] * dt;
    tau -= dt;
  }
}

TableEmulator::TableEmulator(const TableParams& p, uint64_t seed)
    : p_(p),
      rng_(seed),
      vel_counts_(to_vcounts(p.velocity_dps)),
      acc_counts_(to_vcounts(p.accel_dps2)),
      window_counts_(static_cast<uint16_t>(std::clamp<long>(std::lround(p.in_position_window_deg * m::kPosScale), 1, 65535))),
      settle_ms_(static_cast<uint16_t>(std::clamp<long>(std::lround(p.settle_s * 1000), 0, 65535))) {
  const double start = p.start_angle_deg >= 0 ? p.start_angle_deg : std::uniform_real_distribution<double>(0, 360)(rng_);
  if (p.homed_at_start) {
    pos_ = start;  // absolute encoder: drive coordinates are mechanical
    homed_ = true;
  } else {
    mech_offset_ = start;  // incremental encoder counts from 0 at power-on
  }
  ref_ = settle_target_ = pos_;
  target_counts_ = to_counts(pos_);
  if (p.fault != SimFault::kNone) {
    armed_ = p.fault;
    armed_at_ = p.fault_at;
    armed_move_ = p.fault_on_move;
  }
}

std::unique_ptr<TableEmulator> make_table_emulator(const toml::table* cfg, uint64_t seed) {
  return std::make_unique<TableEmulator>(table_params_from_toml(cfg), seed);
}

// Inside IN_POS_WINDOW of the commanded stop point (settling, and IN_POSITION with it).
inline bool TableEmulator::in_window() const {
  return std::fabs(settle_target_ - pos_) <= window_counts_ / m::kPosScale;
}

void TableEmulator::step(double dt_s) {
  std::lock_guard lk(mu_);
  while (dt_s > 1e-12) {
    const double h = std::min(kSubstep, dt_s);
    substep(h);
    dt_s -= h;
  }
}

// Inlined into step()'s loop (about 20 substeps per call in a lockstep run): the servo's
// position and velocity form one serial chain from substep to substep, and a call per substep
// added its overhead to that chain (7.4 % -> 6.0 % of a `paper` run's samples, perf).
[[gnu::always_inline]] inline void TableEmulator::substep(double h) {
  t_ += h;
  hb_acc_ += h;
  while (hb_acc_ >= kHeartbeatPeriod) {
    ++heartbeat_;
    hb_acc_ -= kHeartbeatPeriod;
  }
  if (estop_ && alarm_ != alarm::kEstop) raise(alarm::kEstop);
  if (interlock_open_ && traj_.active) raise(alarm::kInterlock);
  if (p_.comm_timeout_s > 0 && traj_.active && t_ - last_request_t_ > p_.comm_timeout_s) raise(alarm::kCommLost);
  if (!servo_) {
    vel_ = 0;  // the brake holds the axis
    return;
  }
  if (traj_.active) {
    const double tau = t_ - traj_.t0;
    if (traj_.is_move && fault_this_move_ && tau >= armed_at_ * traj_.total) {
      fault_this_move_ = false;
      const SimFault f = armed_;
      armed_ = SimFault::kNone;
      fire(f);
      if (!servo_) return;
    }
    traj_.eval(tau, ref_, ref_v_);
    if (tau >= traj_.total) {
      traj_.active = false;
      if (homing_) finish_homing();
    }
  }
  // Position loop: second order with velocity feed-forward,
  // a = w^2 (r - x) + 2 zeta w (r' - x'), semi-implicit Euler.
  if (stuck_) {
    vel_ = 0;  // seized mechanics: the reference runs away from the axis
  } else {
    // At rest the axis reaches a state the update leaves bit for bit as it is (the velocity a
    // denormal, whose arithmetic is slow): the update is a pure function of these five values,
    // so while they are the ones of the last fixed point it is skipped, with the same bits.
    const ServoInput in{ref_, ref_v_, pos_, vel_, h};
    if (!(fixed_point_ && in.same_bits(*fixed_point_))) {
      const double w = 2 * kPi * p_.servo_bandwidth_hz;
      const double a = w * w * (ref_ - pos_) + 2 * p_.damping * w * (ref_v_ - vel_);
      vel_ += a * h;
      pos_ += vel_ * h;
      const ServoInput out{ref_, ref_v_, pos_, vel_, h};
      if (out.same_bits(in)) fixed_point_ = in;
      else fixed_point_.reset();
    }
  }
  if (std::fabs(ref_ - pos_) > p_.following_error_limit_deg) {
    raise(alarm::kFollowing);
    return;
  }
  if (!traj_.active && in_window()) {
    in_pos_timer_ += h;
    if (in_pos_timer_ >= settle_ms_ / 1000.0) settling_ = false;
  } else {
    in_pos_timer_ = 0;
  }
}

void TableEmulator::plan_move(double target, double vmax, double amax, bool is_move) {
  Trajectory tr;
  tr.t0 = t_;
  tr.r0 = ref_ = pos_;
  tr.v0 = ref_v_ = 0;
  tr.end = target;
  tr.is_move = is_move;
  const double d = std::fabs(target - tr.r0), s = target >= tr.r0 ? 1.0 : -1.0;
  double t_acc = vmax / amax, t_flat = 0;
  if (d >= vmax * t_acc) {
    t_flat = (d - vmax * t_acc) / vmax;
  } else {
    t_acc = std::sqrt(d / amax);
  }
  tr.dur[0] = t_acc;
  tr.dur[1] = t_flat;
  tr.dur[2] = t_acc;
  tr.acc[0] = s * amax;
  tr.acc[2] = -s * amax;
  tr.total = 2 * t_acc + t_flat;
  tr.active = tr.total > 0;
  traj_ = tr;
  settle_target_ = target;
  settling_ = true;
  in_pos_timer_ = 0;
}

// A stop edge never lengthens a stop under way: a HALT after a QUICK_STOP (another master's, or a
// `rig table stop` after `rig table quick-stop`) keeps the quick stop's ramp, as CiA 402's Quick
// stop active ignores halt; a steeper ramp asked later is taken (table-registers.md).
void TableEmulator::plan_stop(double decel) {
  if (!traj_.active || traj_.stop_decel >= decel) return;
  // Nor a move's own final ramp: a QUICK_STOP gentler than ACCEL during a move's deceleration
  // stops on that ramp, at the move's target, instead of coasting past it (table-registers.md).
  if (traj_.stop_decel == 0) {
    double tau = t_ - traj_.t0;
    for (int i = 0; i < 3; ++i) {
      if (tau < traj_.dur[i]) {
        if (traj_.acc[i] * ref_v_ < 0) decel = std::max(decel, std::fabs(traj_.acc[i]));
        break;
      }
      tau -= traj_.dur[i];
    }
  }
  Trajectory tr;
  tr.t0 = t_;
  tr.r0 = ref_;
  tr.v0 = ref_v_;
  const double s = ref_v_ >= 0 ? 1.0 : -1.0;
  tr.dur[0] = std::fabs(ref_v_) / decel;
  tr.acc[0] = -s * decel;
  tr.stop_decel = decel;
  tr.total = tr.dur[0];
  tr.end = ref_ + ref_v_ * tr.total - 0.5 * s * decel * tr.total * tr.total;
  tr.active = tr.total > 0;
  traj_ = tr;
  settle_target_ = tr.end;
  settling_ = true;
  in_pos_timer_ = 0;
  fault_this_move_ = false;
}

// Motion alarms drop the servo and apply the brake; refusals change nothing.
void TableEmulator::raise(uint16_t code) {
  if (m::alarm_safe_to_reset(code)) {
    if (alarm_ == alarm::kNone) alarm_ = code;
    return;
  }
  if (alarm_ == alarm::kNone || m::alarm_safe_to_reset(alarm_) || code == alarm::kEstop) alarm_ = code;
  servo_ = false;
  traj_.active = false;
  homing_ = false;
  settling_ = false;
  fault_this_move_ = false;
  vel_ = 0;
  ref_ = settle_target_ = pos_;
  ref_v_ = 0;
}

void TableEmulator::fire(SimFault f) {
  switch (f) {
    case SimFault::kNone: break;
    case SimFault::kOverTravel: raise(ref_v_ >= 0 ? alarm::kOverTravelPos : alarm::kOverTravelNeg); break;
    case SimFault::kFollowing:
      if (traj_.active) {
        stuck_ = true;
      } else {
        raise(alarm::kFollowing);
      }
      break;
    case SimFault::kDriveFault: raise(alarm::kDriveFault); break;
    case SimFault::kNoAnswer: no_answer_ = true; break;
  }
}

// The home switch sits at mechanical 0: from now on drive coordinates are mechanical.
void TableEmulator::finish_homing() {
  pos_ += mech_offset_;
  ref_ += mech_offset_;
  settle_target_ += mech_offset_;
  mech_offset_ = 0;
  target_counts_ = to_counts(settle_target_);
  homing_ = false;
  homed_ = true;
}

bool TableEmulator::in_position() const {
  // Inside the window for SETTLE_TIME (table-registers.md); with SETTLE_TIME 0 the timer is 0
  // outside the window too, so the window is asked now (a review: a ringing servo read "in
  // position" 1.26 degrees off its target).
  return servo_ && alarm_ == alarm::kNone && !traj_.active && in_pos_timer_ >= settle_ms_ / 1000.0 && in_window();
}
bool TableEmulator::moving() const { return servo_ && (traj_.active || settling_); }

uint16_t TableEmulator::status_word() const {
  uint16_t s = 0;
  const bool alarm = alarm_ != alarm::kNone;
  if (!alarm && !estop_ && !interlock_open_) s |= sts::kReady;
  if (servo_) s |= sts::kServoOn;
  if (moving()) s |= sts::kMoving;
  if (in_position()) s |= sts::kInPosition;
  if (homed_) s |= sts::kHomed;
  if (homing_) s |= sts::kHoming;
  if (alarm) s |= sts::kAlarm;
  if (estop_) s |= sts::kEstop;
  if (alarm_ == alarm::kOverTravelPos) s |= sts::kLimitPos;
  if (alarm_ == alarm::kOverTravelNeg) s |= sts::kLimitNeg;
  if (!interlock_open_) s |= sts::kInterlockOk;
  return s;
}

// ---------------------------------------------------------------- registers

void TableEmulator::image(uint16_t* d, uint16_t* sim) const {
  std::fill(d, d + reg::kBlockEnd, 0);
  d[reg::kControl] = control_;
  d[reg::kStatus] = status_word();
  d[reg::kAlarmCode] = alarm_;
  d[reg::kMapVersion] = reg::kMapVersionValue;
  m::split_u32(heartbeat_, d + reg::kHeartbeat);
  m::split_i32(to_counts(pos_), d + reg::kActualPos);
  m::split_i32(target_counts_, d + reg::kTargetPos);
  m::split_u32(vel_counts_, d + reg::kVelocity);
  m::split_u32(acc_counts_, d + reg::kAccel);
  d[reg::kInPosWindow] = window_counts_;
  d[reg::kSettleTime] = settle_ms_;
  m::split_i32(static_cast<int32_t>(std::lround(vel_ * m::kVelScale)), d + reg::kActualVel);
  m::split_i32(to_counts(ref_ - pos_), d + reg::kFollowErr);
  m::split_i32(to_counts(p_.limit_neg_deg), d + reg::kLimitNeg);
  m::split_i32(to_counts(p_.limit_pos_deg), d + reg::kLimitPos);
  d[reg::kMoveSeq] = move_seq_;
  sim[0] = static_cast<uint16_t>(armed_);
  sim[1] = static_cast<uint16_t>(std::lround(armed_at_ * 1000));
  sim[2] = static_cast<uint16_t>((estop_ ? 1 : 0) | (interlock_open_ ? 2 : 0));
}

namespace {
// The block holding [addr, addr+n), or null when the range is not all inside one.
bool in_block(uint16_t addr, uint16_t n, uint16_t lo, uint16_t hi) {
  return addr >= lo && static_cast<uint32_t>(addr) + n <= hi;
}
bool writable(uint16_t a) {
  return a == reg::kControl || (a >= reg::kTargetPos && a <= reg::kSettleTime) ||
         (a >= reg::kSimFault && a < reg::kSimEnd);
}
}  // namespace

uint8_t TableEmulator::read_registers(uint16_t addr, uint16_t n, uint16_t* out) {
  std::lock_guard lk(mu_);
  last_request_t_ = t_;
  if (n < 1 || n > 125) return exc::kIllegalValue;  // quantity out of range (Modbus spec 6.3)
  uint16_t d[reg::kBlockEnd], sim[reg::kSimEnd - reg::kSimFault];
  image(d, sim);
  if (in_block(addr, n, 0, reg::kBlockEnd)) {
    std::copy(d + addr, d + addr + n, out);
  } else if (in_block(addr, n, reg::kSimFault, reg::kSimEnd)) {
    std::copy(sim + (addr - reg::kSimFault), sim + (addr - reg::kSimFault) + n, out);
  } else {
    return exc::kIllegalAddress;
  }
  return exc::kNone;
}

// Validates the whole request first (an exception reply changes nothing), then
// applies it with the control word last, so target + start can go in one write.
uint8_t TableEmulator::write_registers(uint16_t addr, const uint16_t* v, uint16_t n) {
  std::lock_guard lk(mu_);
  last_request_t_ = t_;
  if (n < 1 || n > 123) return exc::kIllegalValue;
  const uint32_t end = static_cast<uint32_t>(addr) + n;
  if (!in_block(addr, n, 0, reg::kBlockEnd) && !in_block(addr, n, reg::kSimFault, reg::kSimEnd))
    return exc::kIllegalAddress;
  for (uint32_t a = addr; a < end; ++a)
    if (!writable(static_cast<uint16_t>(a))) return exc::kIllegalAddress;
  auto has = [&](uint16_t a) { return a >= addr && a < end; };
  auto val = [&](uint16_t a) { return v[a - addr]; };
  // 32-bit values must be written whole, high word first, in one request.
  for (uint16_t hi : {reg::kTargetPos, reg::kVelocity, reg::kAccel})
    if (has(hi) != has(static_cast<uint16_t>(hi + 1))) return exc::kIllegalAddress;
  const bool busy = traj_.active || homing_;
  if (has(reg::kTargetPos)) {
    if (busy) return exc::kBusy;
    const double deg = m::join_i32(val(reg::kTargetPos), val(reg::kTargetPos + 1)) / m::kPosScale;
    if (deg < p_.limit_neg_deg || deg > p_.limit_pos_deg) return exc::kIllegalValue;
  }
  if (has(reg::kVelocity)) {
    if (busy) return exc::kBusy;
    const uint32_t c = m::join_u32(val(reg::kVelocity), val(reg::kVelocity + 1));
    if (c == 0 || c > to_vcounts(p_.max_velocity_dps)) return exc::kIllegalValue;
  }
  if (has(reg::kAccel)) {
    if (busy) return exc::kBusy;
    const uint32_t c = m::join_u32(val(reg::kAccel), val(reg::kAccel + 1));
    if (c == 0 || c > to_vcounts(p_.max_accel_dps2)) return exc::kIllegalValue;
  }
  if (has(reg::kInPosWindow) && val(reg::kInPosWindow) == 0) return exc::kIllegalValue;
  if (has(reg::kSettleTime) && val(reg::kSettleTime) > 10000) return exc::kIllegalValue;
  if (has(reg::kSimFault) && val(reg::kSimFault) > static_cast<uint16_t>(SimFault::kNoAnswer)) return exc::kIllegalValue;
  if (has(reg::kSimFaultAt) && val(reg::kSimFaultAt) > 1000) return exc::kIllegalValue;
  if (has(reg::kSimInputs) && (val(reg::kSimInputs) & ~3u)) return exc::kIllegalValue;
  if (has(reg::kControl)) {
    const uint16_t w = val(reg::kControl);
    if (w & ~ctl::kAll) return exc::kIllegalValue;
    const uint16_t rising = static_cast<uint16_t>(w & ~control_);
    if ((rising & (ctl::kStart | ctl::kHome)) && busy) return exc::kBusy;
  }
  // Apply.
  if (has(reg::kTargetPos)) target_counts_ = m::join_i32(val(reg::kTargetPos), val(reg::kTargetPos + 1));
  if (has(reg::kVelocity)) vel_counts_ = m::join_u32(val(reg::kVelocity), val(reg::kVelocity + 1));
  if (has(reg::kAccel)) acc_counts_ = m::join_u32(val(reg::kAccel), val(reg::kAccel + 1));
  if (has(reg::kInPosWindow)) window_counts_ = val(reg::kInPosWindow);
  if (has(reg::kSettleTime)) settle_ms_ = val(reg::kSettleTime);
  if (has(reg::kSimInputs)) {
    estop_ = val(reg::kSimInputs) & 1u;
    interlock_open_ = val(reg::kSimInputs) & 2u;
    if (estop_) raise(alarm::kEstop);
    if (interlock_open_ && traj_.active) raise(alarm::kInterlock);
  }
  if (has(reg::kSimFaultAt)) armed_at_ = val(reg::kSimFaultAt) / 1000.0;
  if (has(reg::kSimFault)) {
    const auto f = static_cast<SimFault>(val(reg::kSimFault));
    if (armed_at_ <= 0) {
      armed_ = SimFault::kNone;
      fire(f);
    } else {
      armed_ = f;
      armed_move_ = 0;
    }
  }
  if (has(reg::kControl)) return apply_control(val(reg::kControl));
  return exc::kNone;
}

uint8_t TableEmulator::apply_control(uint16_t w) {
  const uint16_t rising = static_cast<uint16_t>(w & ~control_);
  const uint16_t falling = static_cast<uint16_t>(~w & control_);
  control_ = w;
  if (falling & ctl::kServoOn) {
    servo_ = false;
    traj_.active = false;
    homing_ = false;
    settling_ = false;
    vel_ = 0;
  }
  if (rising & ctl::kAlarmReset) {
    const bool cause_present = (alarm_ == alarm::kEstop && estop_) || (alarm_ == alarm::kInterlock && interlock_open_);
    if (alarm_ != alarm::kNone && !cause_present) {
      alarm_ = alarm::kNone;
      stuck_ = false;
    }
  }
  if ((rising & ctl::kServoOn) && (alarm_ == alarm::kNone || m::alarm_safe_to_reset(alarm_)) && !estop_) {
    servo_ = true;
    ref_ = settle_target_ = pos_;
    ref_v_ = 0;
    settling_ = false;
    in_pos_timer_ = 0;
  }
  if (rising & ctl::kQuickStop) {
    plan_stop(p_.quick_stop_dps2);
    homing_ = false;
  }
  if (rising & ctl::kHalt) {
    plan_stop(acc_counts_ / m::kVelScale);
    homing_ = false;
  }
  auto refused = [&]() {
    if (alarm_ != alarm::kNone && !m::alarm_safe_to_reset(alarm_)) return true;  // the alarm says why
    if (!servo_) {
      raise(alarm::kServoOff);
      return true;
    }
    if (estop_ || interlock_open_) {
      raise(alarm::kNotReady);
      return true;
    }
    return (w & ctl::kHalt) != 0;
  };
  if ((rising & ctl::kHome) && !refused()) {
    homing_ = true;
    homed_ = false;
    ++move_seq_;
    plan_move(pos_ - (pos_ + mech_offset_), p_.home_velocity_dps, acc_counts_ / m::kVelScale, false);
    if (!traj_.active) finish_homing();
  }
  if ((rising & ctl::kStart) && !refused()) {
    if (!homed_) {
      raise(alarm::kNotHomed);
      return exc::kNone;
    }
    ++move_seq_;
    ++moves_started_;
    fault_this_move_ = armed_ != SimFault::kNone && (armed_move_ == 0 || armed_move_ == moves_started_);
    rep_err_ = p_.repeatability_deg > 0 ? std::normal_distribution<double>(0, p_.repeatability_deg)(rng_) : 0.0;
    plan_move(target_counts_ / m::kPosScale, vel_counts_ / m::kVelScale, acc_counts_ / m::kVelScale, true);
  }
  return exc::kNone;
}

// ---------------------------------------------------------------- hooks

double TableEmulator::actual_angle_deg() const {
  std::lock_guard lk(mu_);
  return pos_ + mech_offset_ + rep_err_;
}

double TableEmulator::time_s() const {
  std::lock_guard lk(mu_);
  return t_;
}

bool TableEmulator::answering() const {
  std::lock_guard lk(mu_);
  return !no_answer_;
}

void TableEmulator::inject(SimFault f, double at_fraction) {
  std::lock_guard lk(mu_);
  if (at_fraction <= 0) {
    fire(f);
    return;
  }
  armed_ = f;
  armed_at_ = std::min(at_fraction, 1.0);
  armed_move_ = 0;
  // A move already under way takes the fault too.
  fault_this_move_ = traj_.active && traj_.is_move;
}

void TableEmulator::clear_no_answer() {
  std::lock_guard lk(mu_);
  no_answer_ = false;
}

void TableEmulator::set_estop(bool pressed) {
  std::lock_guard lk(mu_);
  estop_ = pressed;
  if (pressed) raise(alarm::kEstop);
}

void TableEmulator::set_interlock(bool closed) {
  std::lock_guard lk(mu_);
  interlock_open_ = !closed;
  if (interlock_open_ && traj_.active) raise(alarm::kInterlock);
}

TableEmulator::Snapshot TableEmulator::snapshot() const {
  std::lock_guard lk(mu_);
  Snapshot s{};
  s.position_deg = pos_;
  s.velocity_dps = vel_;
  s.reference_deg = ref_;
  s.mechanical_deg = pos_ + mech_offset_ + rep_err_;
  s.status = status_word();
  s.alarm_code = alarm_;
  s.move_seq = move_seq_;
  s.servo_on = servo_;
  s.homed = homed_;
  s.homing = homing_;
  s.moving = moving();
  s.in_position = in_position();
  s.moves_started = moves_started_;
  return s;
}

}  // namespace rig::plant
