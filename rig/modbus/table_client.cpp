#include "rig/modbus/table_client.hpp"

#include <netdb.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include <filesystem>
#include <tuple>

#include "rig/core/toml_util.hpp"
#include "rig/modbus/cia402_client.hpp"
#include "rig/modbus/motion_text.hpp"
#include "rig/core/path_kind.hpp"

namespace rig::modbus {

namespace {

using detail::deg_str;
using detail::deg_str_past;
using detail::hex4;
using detail::secs;
using detail::trapezoid_time;

constexpr double kRestTimeoutS = 30.0;

}  // namespace

DriveState decode_drive_state(const std::vector<uint16_t>& r) {
  DriveState d;
  d.control = r[reg::kControl];
  d.status = r[reg::kStatus];
  d.alarm_code = r[reg::kAlarmCode];
  d.heartbeat = join_u32(r[reg::kHeartbeat], r[reg::kHeartbeat + 1]);
  d.actual_deg = join_i32(r[reg::kActualPos], r[reg::kActualPos + 1]) / kPosScale;
  d.target_deg = join_i32(r[reg::kTargetPos], r[reg::kTargetPos + 1]) / kPosScale;
  d.velocity_dps = join_u32(r[reg::kVelocity], r[reg::kVelocity + 1]) / kVelScale;
  d.accel_dps2 = join_u32(r[reg::kAccel], r[reg::kAccel + 1]) / kVelScale;
  d.window_deg = r[reg::kInPosWindow] / kPosScale;
  d.settle_s = r[reg::kSettleTime] / 1000.0;
  d.actual_vel_dps = join_i32(r[reg::kActualVel], r[reg::kActualVel + 1]) / kVelScale;
  d.following_err_deg = join_i32(r[reg::kFollowErr], r[reg::kFollowErr + 1]) / kPosScale;
  d.limit_neg_deg = join_i32(r[reg::kLimitNeg], r[reg::kLimitNeg + 1]) / kPosScale;
  d.limit_pos_deg = join_i32(r[reg::kLimitPos], r[reg::kLimitPos + 1]) / kPosScale;
  d.move_seq = r[reg::kMoveSeq];
  return d;
}

TableStatus to_table_status(const DriveState& d) {
  TableStatus s;
  s.actual_deg = d.actual_deg;
  s.target_deg = d.target_deg;
  s.ready = d.has(sts::kReady);
  s.servo_on = d.has(sts::kServoOn);
  s.homed = d.has(sts::kHomed);
  s.homing = d.has(sts::kHoming);
  s.moving = d.has(sts::kMoving);
  s.in_position = d.has(sts::kInPosition);
  s.alarm = d.has(sts::kAlarm);
  s.estop = d.has(sts::kEstop);
  s.interlock_ok = d.has(sts::kInterlockOk);
  s.limit_pos = d.has(sts::kLimitPos);
  s.limit_neg = d.has(sts::kLimitNeg);
  s.has_limit_switches = true;
  s.alarm_code = d.alarm_code;
  s.alarm_text = alarm_text(d.alarm_code);
  s.heartbeat = d.heartbeat;
  return s;
}

TableClient::TableClient(std::unique_ptr<RegisterTransport> transport, Clock& clock, TableOptions opt)
    : transport_(std::move(transport)), clock_(clock), opt_(std::move(opt)) {}

std::string TableClient::describe() const { return transport_->describe(); }

namespace {
const char* const kForCia402 =
    "for a CiA 402 drive give --drive cia402 --drive-map FILE, or drive and drive_map in the hardware file's [table]";
const char* const kNoStatusBlock = "the drive has no rig-v1 status registers at 0..24";

// Why a status block is not a rig-v1 drive's ("" when it may be): MAP_VERSION, and what the map
// itself rules out (docs/table-registers.md): a STATUS bit above 10, a CONTROL bit the drive
// refuses to take, soft limits not in order, a zero profile velocity, acceleration or window, a
// settle time above 10 s. MAP_VERSION alone let a CiA 402 drive through whose modes of operation
// (1 after a profile move) sit at register 3 (a review).
std::string rig_v1_block_problem(const std::vector<uint16_t>& r) {
  auto at = [](uint16_t a) { return "register " + std::to_string(a); };
  if (r[reg::kMapVersion] != reg::kMapVersionValue)
    return "MAP_VERSION (" + at(reg::kMapVersion) + ") reads " + std::to_string(r[reg::kMapVersion]) +
           "; this rig speaks register map version " + std::to_string(reg::kMapVersionValue) + " (drive = \"rig-v1\")";
  std::string bad;
  auto no = [&](const std::string& what) { bad += (bad.empty() ? "" : ", ") + what; };
  if (r[reg::kStatus] >> 11) no("STATUS (" + at(reg::kStatus) + ") has bits above 10 (" + std::to_string(r[reg::kStatus]) + ")");
  if (r[reg::kControl] & ~ctl::kAll) no("CONTROL (" + at(reg::kControl) + ") holds bits the map refuses (" + std::to_string(r[reg::kControl]) + ")");
  if (join_i32(r[reg::kLimitNeg], r[reg::kLimitNeg + 1]) >= join_i32(r[reg::kLimitPos], r[reg::kLimitPos + 1]))
    no("LIMIT_NEG (" + at(reg::kLimitNeg) + ") is not below LIMIT_POS");
  if (join_u32(r[reg::kVelocity], r[reg::kVelocity + 1]) == 0) no("VELOCITY (" + at(reg::kVelocity) + ") is 0");
  if (join_u32(r[reg::kAccel], r[reg::kAccel + 1]) == 0) no("ACCEL (" + at(reg::kAccel) + ") is 0");
  if (r[reg::kInPosWindow] == 0) no("IN_POS_WINDOW (" + at(reg::kInPosWindow) + ") is 0");
  if (r[reg::kSettleTime] > 10000) no("SETTLE_TIME (" + at(reg::kSettleTime) + ") is above 10000 ms");
  return bad.empty() ? "" : "MAP_VERSION reads 1, but " + bad + ": not a rig-v1 drive";
}
}  // namespace

std::optional<std::pair<double, double>> TableClient::travel_deg(const CancelToken& cancel) {
  const DriveState d = read_drive(cancel);
  return std::pair{d.limit_neg_deg, d.limit_pos_deg};
}

DriveState TableClient::read_drive(const CancelToken& cancel) {
  std::vector<uint16_t> regs;
  try {
    regs = transport_->read(0, reg::kBlockEnd, cancel);
  } catch (const ModbusError& e) {
    // What answers in another protocol before this client knew the drive (an HTTP server at the
    // port) is no drive: said so, nothing sent (a technician's re-test: `status` said only
    // "protocol violation", `move` "stop not sent (the table may still be moving)").
    if (e.foreign_reply && !identified_)
      throw detail::NotThisDriveError(std::string(e.what()) + " (" + kForeignPeer + "); nothing sent");
    // A drive without rig-v1's status block (a CiA 402 drive, another map) refuses the read
    // itself; say what to try (a technician's review: "exception 0x02" alone).
    if (e.exception_code != exc::kIllegalAddress) throw;
    const std::string why = std::string(e.what()) + " (" + kNoStatusBlock + ": " + kForCia402 + ")";
    if (!identified_) throw detail::NotThisDriveError(why + "; nothing sent");  // e.what() names the device
    throw ModbusError(why, e.exception_code, e.timeout, e.foreign_reply);
  }
  // A drive speaking another map version, or another map, would be misread register by register.
  // Before this client's first write: not the drive, nothing sent, no stop. Later (a drive that
  // changed under a running call): a fault, whose stop is tried as for any other.
  if (const std::string why = rig_v1_block_problem(regs); !why.empty()) {
    if (!identified_) throw detail::NotThisDriveError(describe() + ": " + why + " (" + kForCia402 + "); nothing sent");
    throw HardwareError(describe() + ": " + why);
  }
  identified_ = true;
  DriveState d = decode_drive_state(regs);
  control_ = d.control;
  last_actual_deg_ = d.actual_deg;
  have_actual_ = true;
  angle_seen(d.actual_deg);
  return d;
}

TableStatus TableClient::status() {
  try {
    return to_table_status(read_drive());
  } catch (const ModbusError& e) {
    throw HardwareError(std::string("table status: ") + e.what());
  }
}

// Within a move or homing run, never over a stop asked meanwhile (StopLatch).
void TableClient::write_control(uint16_t word, const CancelToken& cancel) {
  stops_.write_command(word, cancel, [&] {
    transport_->write(reg::kControl, {word}, cancel);
    control_ = word;
  });
}

std::string TableClient::at(const DriveState& d) const { return " at " + deg_str(d.actual_deg); }

void TableClient::fail_on_alarm(const std::string& doing, const DriveState& d) {
  if (!d.has(sts::kAlarm)) return;
  std::string msg = doing + ": alarm " + hex4(d.alarm_code) + " " + alarm_text(d.alarm_code) + at(d);
  if (d.alarm_code == alarm::kEstop) {
    msg += " (release the e-stop, then `rig table reset`)";
  } else if (d.alarm_code == alarm::kInterlock) {
    msg += " (close the interlock, then `rig table reset`)";
  } else if (!alarm_safe_to_reset(d.alarm_code)) {
    msg += " (inspect the table, then `rig table reset`)";
  }
  throw HardwareError(msg);
}

void TableClient::watch_heartbeat(const std::string& doing, const DriveState& d, double& last_change_s,
                                  uint32_t& last_hb) {
  const double now = clock_.now_s();
  if (d.heartbeat != last_hb) {
    last_hb = d.heartbeat;
    last_change_s = now;
  } else if (now - last_change_s > opt_.heartbeat_timeout_s) {
    throw HardwareError(doing + ": drive heartbeat frozen at " + std::to_string(d.heartbeat) + " for " +
                        secs(now - last_change_s) + " (drive controller not running)" + at(d));
  }
}

void TableClient::apply_profile_once(const CancelToken& cancel) {
  if (profile_applied_) return;
  auto write = [&](uint16_t addr, std::vector<uint16_t> regs, const char* key, double value) {
    detail::write_setting(opt_.where(key), key, value, [&] { transport_->write(addr, regs, cancel); });
  };
  uint16_t w[2];
  if (opt_.velocity_dps) {
    split_u32(static_cast<uint32_t>(std::lround(*opt_.velocity_dps * kVelScale)), w);
    write(reg::kVelocity, {w[0], w[1]}, "velocity_dps", *opt_.velocity_dps);
  }
  if (opt_.accel_dps2) {
    split_u32(static_cast<uint32_t>(std::lround(*opt_.accel_dps2 * kVelScale)), w);
    write(reg::kAccel, {w[0], w[1]}, "accel_dps2", *opt_.accel_dps2);
  }
  if (opt_.in_position_window_deg)
    write(reg::kInPosWindow, {static_cast<uint16_t>(std::lround(*opt_.in_position_window_deg * kPosScale))},
          "in_position_window_deg", *opt_.in_position_window_deg);
  if (opt_.drive_settle_s)
    write(reg::kSettleTime, {static_cast<uint16_t>(std::lround(*opt_.drive_settle_s * 1000))}, "drive_settle_s",
          *opt_.drive_settle_s);
  profile_applied_ = true;
}

// Brings the drive to "servo on, no alarm, ready": resets only the alarms that
// are command refusals; anything else is reported for a technician.
void TableClient::prepare_motion(const std::string& doing, const CancelToken& cancel) {
  DriveState d = read_drive(cancel);
  if (d.has(sts::kAlarm) && alarm_safe_to_reset(d.alarm_code) && !d.has(sts::kEstop) && d.has(sts::kInterlockOk)) {
    const auto servo = static_cast<uint16_t>(control_ & ctl::kServoOn);
    write_control(servo, cancel);
    write_control(servo | ctl::kAlarmReset, cancel);
    write_control(servo, cancel);
    d = read_drive(cancel);
  }
  fail_on_alarm(doing, d);
  d = wait_at_rest(doing, d, cancel);
  // With the remedy, as the alarms carry theirs (a technician's review: "interlock open" alone).
  if (d.has(sts::kEstop)) throw HardwareError(doing + ": emergency stop pressed" + at(d) + " (release the e-stop, then try again)");
  if (!d.has(sts::kInterlockOk))
    throw HardwareError(doing + ": interlock open" + at(d) + " (close the table's guard or door, then try again)");
  // Clears HALT / QUICK_STOP / START / HOME so the next edge is seen.
  if (!d.has(sts::kServoOn)) {
    write_control(0, cancel);
    write_control(ctl::kServoOn, cancel);
    const double t0 = clock_.now_s();
    for (;;) {
      d = read_drive(cancel);
      fail_on_alarm(doing, d);
      if (d.has(sts::kServoOn)) break;
      if (clock_.now_s() - t0 > opt_.ack_timeout_s)
        throw HardwareError(doing + ": servo did not switch on within " + secs(opt_.ack_timeout_s) + at(d));
      clock_.sleep_for(opt_.poll_s, cancel);
    }
  } else {
    write_control(ctl::kServoOn, cancel);
  }
  apply_profile_once(cancel);
}

// A table still coasting from a stop (or moved by another master) must come
// to rest before a new command; bounded so a runaway is reported.
DriveState TableClient::wait_at_rest(const std::string& doing, DriveState d, const CancelToken& cancel) {
  const double t0 = clock_.now_s();
  while (d.has(sts::kMoving) || d.has(sts::kHoming)) {
    if (clock_.now_s() - t0 > kRestTimeoutS)
      throw HardwareError(doing + ": the table is still moving after " + secs(kRestTimeoutS) +
                          " (another Modbus master?)" + at(d));
    clock_.sleep_for(opt_.poll_s, cancel);
    d = read_drive(cancel);
    fail_on_alarm(doing, d);
  }
  return d;
}

template <class Body>
void TableClient::guarded(const std::string& doing, Body body) {
  detail::guarded_call(
      doing, body,
      [this] { return have_actual_ ? " (last seen at " + deg_str(last_actual_deg_) + ")" : std::string(); },
      [this] { return stops_.send_again([this] { quick_stop(); }, [this] { stop(); }); },
      [this] { return last_stop_error(); });
}

// A stop asked of this client since the operation began ends it at the next poll, whether or not
// it reached the drive (one that did not leaves no HALT to read back: the move went on and
// reported success, a review). Else a stop read back in CONTROL is another master's, over whose
// command no halt of ours is sent (TakenOverError).
void TableClient::fail_on_stop_bits(const std::string& doing, const DriveState& d) const {
  if (stops_.since_begin()) throw HardwareError(doing + ": " + stops_.halted_by() + at(d));
  if (!(d.control & (ctl::kHalt | ctl::kQuickStop))) return;
  throw detail::TakenOverError(doing + ": " + ((d.control & ctl::kHalt) ? "halted" : "quick-stopped") +
                               " by another master (CONTROL reads " + hex4(d.control) + ")" + at(d));
}

// The servo read off mid-run with no alarm: another master's CONTROL without SERVO_ON (the drive
// brakes and the table stays short of its goal; a move waited out its timeout, 27.6 s in a review)
// ends the call at once with no halt of ours over it, as another master's stop does; the drive's
// own (CONTROL still SERVO_ON) is a fault like any other.
void TableClient::fail_on_servo_off(const std::string& doing, const DriveState& d) const {
  if (d.has(sts::kServoOn)) return;
  // A drive may set E-STOP or clear INTERLOCK_OK a poll before ALARM (a code review).
  if (d.has(sts::kEstop)) throw HardwareError(doing + ": emergency stop pressed (servo off)" + at(d));
  if (!d.has(sts::kInterlockOk)) throw HardwareError(doing + ": interlock open (servo off)" + at(d));
  if (!(d.control & ctl::kServoOn))
    throw detail::TakenOverError(doing + ": servo switched off by another master (CONTROL reads " + hex4(d.control) +
                                 ")" + at(d));
  throw HardwareError(doing + ": the drive switched its servo off (no alarm; CONTROL reads " + hex4(d.control) + ")" +
                      at(d));
}

void TableClient::home(const CancelToken& cancel) {
  const std::string doing = "home";
  const detail::StopLatch::Scope operation(stops_, doing);
  guarded(doing, [&] {
    prepare_motion(doing, cancel);
    const uint16_t seq0 = read_drive(cancel).move_seq;
    write_control(ctl::kServoOn | ctl::kHome, cancel);
    const double t0 = clock_.now_s();
    double hb_t = t0;
    uint32_t hb = 0;
    bool acked = false;
    bool seen_running = false;  // HOMING or MOVING read once after the acknowledge (for the message)
    detail::HeldFor ended;      // the run reads ended short of its home
    for (;;) {
      const DriveState d = read_drive(cancel);
      fail_on_alarm(doing, d);
      watch_heartbeat(doing, d, hb_t, hb);
      const double now = clock_.now_s();
      const double el = now - t0;
      if (!acked) {
        if (d.move_seq != seq0) {
          acked = true;
          write_control(ctl::kServoOn, cancel);
        } else if (el > opt_.ack_timeout_s) {
          throw HardwareError(doing + ": home command not acknowledged within " + secs(opt_.ack_timeout_s) + at(d));
        }
      }
      if (acked && d.has(sts::kHomed) && !d.has(sts::kHoming) && !d.has(sts::kMoving)) return;
      if (acked) {
        // Another master's stop ends the homing run as it ends a move; it waited out
        // home_timeout_s before (a review). A run stopped and released again leaves no HALT to
        // read back, only a drive at rest that is neither homed nor homing: taken for one once
        // the state has held ended_short_s after the acknowledge (a drive may set HOMED a few
        // cycles after it clears HOMING, or HOMING a few after MOVE_SEQ; a review). Also when the
        // run was never seen under way (stopped and released before the first poll): it waited
        // out home_timeout_s before. The halt follows as for any fault: a drive that only paused
        // must not move on after the rig gave up on it (a review).
        fail_on_stop_bits(doing, d);
        fail_on_servo_off(doing, d);
        const bool running = d.has(sts::kHoming) || d.has(sts::kMoving);
        seen_running = seen_running || running;
        const double ended_s = ended(!running && !d.has(sts::kHomed), now);
        if (ended_s >= opt_.ended_short_s)
          throw HardwareError(doing + ": homing ended without reaching the home switch (HOMED not set for " +
                              secs(ended_s) +
                              (seen_running ? " after the run stopped"
                                            : " after the acknowledge, and the run was never seen under way") +
                              "; stopped by another Modbus master?)" + at(d));
      }
      if (el > opt_.home_timeout_s)
        throw HardwareError(doing + ": not homed after " + secs(el) + (d.has(sts::kHoming) ? " (still homing)" : "") +
                            at(d));
      clock_.sleep_for(opt_.poll_s, cancel);
    }
  });
}

void TableClient::move_to(double deg, const CancelToken& cancel) {
  const std::string doing = "move to " + deg_str(deg);
  const detail::StopLatch::Scope operation(stops_, doing);
  if (!std::isfinite(deg) || std::fabs(deg) > 200000.0) throw ConfigError(doing + ": not a valid angle");
  // Refused before anything is written (no servo-on, no halt): a table that is not homed, a
  // target outside the drive's limits. The drive was left powered with HALT set before (a review).
  const DriveState d0 = detail::read_before_motion([&] { return read_drive(cancel); },
                                                    [&](auto body) { guarded(doing, body); });
  // The drive takes counts (kPosScale per degree) and holds its limits in counts: the angle is
  // judged as it will be written (369.99996° and 370.00004° are both 370.0000°; one was refused
  // at a limit of 370.0000°, a review).
  const auto counts = static_cast<int32_t>(std::lround(deg * kPosScale));
  const double written = counts / kPosScale;
  // Before anything is written it says so, as every refusal there does (docs/table-registers.md).
  auto refuse_outside = [&](const DriveState& d, bool nothing_sent) {
    if (written < d.limit_neg_deg || written > d.limit_pos_deg)
      throw ConfigError("move to " + deg_str_past(deg, written < d.limit_neg_deg ? d.limit_neg_deg : d.limit_pos_deg) +
                        ": outside the drive's travel limits [" + deg_str(d.limit_neg_deg) + ", " +
                        deg_str(d.limit_pos_deg) + "]" + (nothing_sent ? "; nothing sent" : ""));
  };
  // A target no drive state makes reachable is the command's mistake (exit 2) before the table's
  // state (not homed: exit 4) is: the order gave exit 4 for `move 400` on an unhomed table (a review).
  refuse_outside(d0, true);
  if (!d0.has(sts::kHomed))
    throw NotReadyError(doing + ": table not homed (run `rig table home` first)" + at(d0) + "; nothing sent");
  guarded(doing, [&] {
    prepare_motion(doing, cancel);
    DriveState d = read_drive(cancel);
    if (!d.has(sts::kHomed)) throw NotReadyError(doing + ": table not homed (run `rig table home` first)" + at(d));
    refuse_outside(d, false);
    uint16_t w[2];
    split_i32(counts, w);
    transport_->write(reg::kTargetPos, {w[0], w[1]}, cancel);
    const uint16_t seq0 = d.move_seq;
    const double timeout = opt_.move_timeout_s > 0
                               ? opt_.move_timeout_s
                               : 2 * trapezoid_time(deg - d.actual_deg, d.velocity_dps, d.accel_dps2) + d.settle_s +
                                     opt_.settle_s + 10.0;
    write_control(ctl::kServoOn | ctl::kStart, cancel);
    const double t0 = clock_.now_s();
    double hb_t = t0;
    detail::HeldFor in_position;
    detail::HeldFor stopped_short;  // in position at a stop point off the target, and staying there
    double short_at = NAN;          // where that reading began
    bool seen_moving = false;       // MOVING read once after the acknowledge
    uint32_t hb = d.heartbeat;
    bool acked = false;
    for (;;) {
      d = read_drive(cancel);
      fail_on_alarm(doing, d);
      watch_heartbeat(doing, d, hb_t, hb);
      const double now = clock_.now_s();
      if (!acked) {
        if (d.move_seq != seq0) {
          acked = true;
          write_control(ctl::kServoOn, cancel);  // drop START: the next move needs a new edge
        } else if (now - t0 > opt_.ack_timeout_s) {
          throw HardwareError(doing + ": start not acknowledged within " + secs(opt_.ack_timeout_s) + at(d));
        }
      }
      if (acked) {
        // A drive that powers up again mid-move comes back unhomed with its power-on target:
        // say so, rather than blame the target's change on another master.
        if (!d.has(sts::kHomed) && !d.has(sts::kHoming))
          throw HardwareError(doing + ": the drive reports not homed" + (d.has(sts::kServoOn) ? "" : " and servo off") +
                              " mid-move (the drive restarted or was power-cycled?)" + at(d));
        // Another master's set-point or stop: the call ends at once, with no halt of ours over
        // its motion (guarded_call); a stop reads back in CONTROL (ours: stops_, as the read
        // overwrote control_). Another master's stop waited out the move timeout (a review).
        if (std::lround(d.target_deg * kPosScale) != counts)
          throw detail::TakenOverError(doing + ": target register changed to " + deg_str(d.target_deg) +
                                       " (another Modbus master?)" + at(d));
        fail_on_stop_bits(doing, d);
        fail_on_servo_off(doing, d);
        const double off = std::fabs(d.actual_deg - deg);
        const bool ok = d.has(sts::kInPosition) && !d.has(sts::kMoving) && off <= opt_.tolerance_deg;
        if (in_position(ok, now) >= opt_.settle_s) return;
        // IN_POSITION is "at rest at the last commanded stop point" (table-registers.md): read off
        // the target, beyond the client's tolerance and the drive's window, after the move was
        // seen under way, the move was stopped short. A HALT or QUICK_STOP set and released again
        // between two polls leaves nothing else to read (the move timeout, 31.6 s in a review,
        // found it before). Held ended_short_s with the table staying within the band where
        // the reading began, at least ten bands off the target: a servo still ringing or creeping
        // towards it moves on by more (a review: with SETTLE_TIME 0 a 0.3 Hz servo read in
        // position 1.26 degrees off its target for over 1 s, and a drive may keep IN_POSITION
        // once set; at 0.014 degrees it crept by less than the band in 1 s). A stop nearer than
        // that is left to the move timeout. The halt follows as for any fault.
        seen_moving = seen_moving || d.has(sts::kMoving);
        const double band = std::max(opt_.tolerance_deg, d.window_deg);
        const bool short_stop = seen_moving && d.has(sts::kInPosition) && !d.has(sts::kMoving) && off > 10 * band;
        if (!short_stop || !(std::fabs(d.actual_deg - short_at) <= band)) {
          stopped_short(false, now);  // not so, or moved on: the hold starts again from here
          short_at = short_stop ? d.actual_deg : NAN;
        }
        const double short_s = stopped_short(short_stop, now);
        if (short_s >= opt_.ended_short_s)
          throw HardwareError(doing + ": stopped " + deg_str(off) + " off target, in position at that stop point for " +
                              secs(short_s) + " (halted and released by another Modbus master?)" + at(d));
      }
      if (now - t0 > timeout) {
        std::string state = d.has(sts::kMoving) ? "still moving" : "not in position";
        if (!d.has(sts::kMoving) && std::fabs(d.actual_deg - deg) > opt_.tolerance_deg)
          state = "stopped " + deg_str(std::fabs(d.actual_deg - deg)) + " off target (tolerance " +
                  deg_str(opt_.tolerance_deg) + ")";
        throw HardwareError(doing + ": timed out after " + secs(now - t0) + ", " + state + at(d));
      }
      clock_.sleep_for(opt_.poll_s, cancel);
    }
  });
}

void TableClient::reset_alarm(const CancelToken& cancel) {
  const std::string doing = "alarm reset";
  try {
    DriveState d = read_drive(cancel);
    if (!d.has(sts::kAlarm)) return;
    if (d.has(sts::kEstop)) throw HardwareError(doing + ": refused, emergency stop pressed (release it first)");
    if (!d.has(sts::kInterlockOk)) throw HardwareError(doing + ": refused, interlock open (close the table's guard or door first)");
    const auto servo = static_cast<uint16_t>(control_ & ctl::kServoOn);
    write_control(servo, cancel);
    write_control(servo | ctl::kAlarmReset, cancel);
    write_control(servo, cancel);
    d = read_drive(cancel);
    if (d.has(sts::kAlarm))
      throw HardwareError(doing + ": alarm " + hex4(d.alarm_code) + " " + alarm_text(d.alarm_code) +
                          " persists (its cause is still present)");
  } catch (const ModbusError& e) {
    throw HardwareError(doing + ": link failure: " + e.what());
  }
}

void TableClient::set_stop_note(std::string note) noexcept {
  try {
    std::lock_guard lk(stop_mu_);
    last_stop_note_.swap(note);
  } catch (...) {
  }
}

void TableClient::send_stop(uint16_t bit, const char* name) noexcept {
  detail::deliver_stop(
      name,
      [&] {
        const bool known = identified_.load();  // read with the word it qualifies
        const uint16_t now = control_.load();
        const auto servo = static_cast<uint16_t>(now & ctl::kServoOn);
        // Unread, the servo bit is written cleared: a drive that takes the stop then also switches
        // its servo off (the table stops on its brake), where a set bit could enable an idle servo.
        if (!known) try {  // (a note that cannot be built never keeps the stop from going out)
            set_stop_note(std::string(name) + " written with SERVO_ON cleared (CONTROL " + hex4(bit) +
                          "): the drive's state could not be read before it, so a drive that takes it also switches "
                          "its servo off");
          } catch (...) {
          }
        if (now & bit) transport_->write(reg::kControl, {servo}, CancelToken{}, true);  // re-arm the edge
        transport_->write(reg::kControl, {static_cast<uint16_t>(servo | bit)}, CancelToken{}, true);
        control_ = static_cast<uint16_t>(servo | bit);
      },
      stop_mu_, last_stop_error_);
}

// A client that has not yet read a rig-v1 status block reads it (one urgent request) before its
// first stop: a device without the block, or with another MAP_VERSION, is not a rig-v1 drive, and
// a stop bit written into its registers is a guess (a review: HALT alone, 0x0100, is Disable
// voltage on a CiA 402 drive), nor is one that answered in another protocol. A read that fails
// otherwise (silence, a Modbus reply that breaks the protocol, a broken connection) still sends:
// the link decides then.
bool TableClient::refuse_stop_to_unknown(const char* name) noexcept {
  if (identified_) return false;
  std::string why;
  try {
    const std::vector<uint16_t> regs = transport_->read(0, reg::kBlockEnd, CancelToken{}, true);
    if (regs.size() < reg::kBlockEnd) return false;  // (never: the transport checks the count)
    why = rig_v1_block_problem(regs);
    if (why.empty()) {
      identified_ = true;
      control_ = decode_drive_state(regs).control;  // the stop keeps SERVO_ON as the drive holds it
    }
  } catch (const ModbusError& e) {
    if (e.exception_code == exc::kIllegalAddress) why = std::string(e.what()) + " (" + kNoStatusBlock + ": " + kForCia402 + ")";
    // A gateway answering that no device answers at this unit id: whatever is there (if anything)
    // was not recognised as the drive, so nothing is written to it (a review: the stop went out).
    else if (e.exception_code == exc::kGatewayPath || e.exception_code == exc::kGatewayTarget) why = e.what();
    // What answered speaks another protocol (an HTTP server's error page): not the drive, so no
    // stop bit goes into it (a review: an HTTP server got the stop's writes).
    else if (e.foreign_reply) why = std::string(e.what()) + " (" + kForeignPeer + ")";
  } catch (...) {
  }
  if (why.empty()) return false;
  try {
    why = std::string(name) + " not sent (the table may still be moving): " + why;
  } catch (...) {
  }
  detail::record_stop(stop_mu_, last_stop_error_, std::move(why));
  return true;
}

// Each stop asked for, sent or not, ends a move or homing run under way before its next command
// word (StopLatch), and a move polling meanwhile reads it back in CONTROL as this client's own.
// A stop never weakens a quick stop of this client's that still stands: no HALT then (on a drive
// whose HALT edge re-planned the rest on the profile ramp: 22.8° of travel where the quick stop
// alone took 6.6°, an outside review; the register map now forbids it, table-registers.md, and
// this keeps a drive that does it anyway safe); the quick stop's own fate stays the one said.
void TableClient::stop() noexcept {
  set_stop_note({});  // this stop's, not an earlier one's
  const detail::StopLatch::Asking counted(stops_, false);
  if (stops_.quick_stop_stands()) return;
  if (!refuse_stop_to_unknown("stop")) send_stop(ctl::kHalt, "stop");
}
void TableClient::quick_stop() noexcept {
  set_stop_note({});
  const detail::StopLatch::Asking counted(stops_, true);
  if (refuse_stop_to_unknown("quick stop")) return;
  send_stop(ctl::kQuickStop, "quick stop");
  stops_.quick_stop_sent(last_stop_error().empty());
}

// ---------------------------------------------------------------- config

TableOptions table_options_from_toml(const toml::table& t) {
  TableOptions o;
  o.tolerance_deg = cfg::get_number(t, "tolerance_deg", o.tolerance_deg, 0.0, 10.0);
  o.settle_s = cfg::get_number(t, "settle_s", o.settle_s, 0.0, 600.0);
  o.poll_s = cfg::get_number(t, "poll_s", o.poll_s, 0.001, 10.0);
  o.move_timeout_s = cfg::get_number(t, "move_timeout_s", o.move_timeout_s, 0.0, 3600.0);
  o.home_timeout_s = cfg::get_number(t, "home_timeout_s", o.home_timeout_s, 0.1, 3600.0);
  o.ack_timeout_s = cfg::get_number(t, "ack_timeout_s", o.ack_timeout_s, 0.01, 60.0);
  o.heartbeat_timeout_s = cfg::get_number(t, "heartbeat_timeout_s", o.heartbeat_timeout_s, 0.05, 600.0);
  o.ended_short_s = cfg::get_number(t, "ended_short_s", o.ended_short_s, 0.05, 600.0);
  o.unacked_motion_s = cfg::get_number(t, "unacked_motion_s", o.unacked_motion_s, 0.01, 60.0);
  if (t.contains("velocity_dps")) o.velocity_dps = cfg::get_number(t, "velocity_dps", {}, 0.001, 4000.0);
  if (t.contains("accel_dps2")) o.accel_dps2 = cfg::get_number(t, "accel_dps2", {}, 0.001, 4000.0);
  if (t.contains("in_position_window_deg"))
    o.in_position_window_deg = cfg::get_number(t, "in_position_window_deg", {}, 0.0001, 6.5);
  if (t.contains("drive_settle_s")) o.drive_settle_s = cfg::get_number(t, "drive_settle_s", {}, 0.0, 65.0);
  for (const char* k : {"velocity_dps", "accel_dps2", "in_position_window_deg", "drive_settle_s"})
    if (const toml::node* n = t.get(k)) o.written_at[k] = cfg::where(*n);
  return o;
}

LinkOptions link_options_from_toml(const toml::table& t) {
  LinkOptions l;
  // 1..247: the Modbus serial-line addresses (0 is broadcast: a drive never answers it).
  l.unit = static_cast<int>(cfg::get_int(t, "unit", l.unit, 1, 247));
  l.response_timeout_s = cfg::get_number(t, "response_timeout_s", l.response_timeout_s, 0.01, 10.0);
  l.retries = static_cast<int>(cfg::get_int(t, "retries", l.retries, 0, 10));
  l.backoff_s = cfg::get_number(t, "backoff_s", l.backoff_s, 0.0, 10.0);
  return l;
}

namespace {
// Where the drive protocol was said, for a key refused because of it: the file's line, or the
// command line's --drive (which overrides the file's; the refused key's line alone then blamed a
// file that says drive = "cia402"), or the default.
std::string drive_said(const toml::table& t, const std::string& drive) {
  const toml::node* n = t.get("drive");
  const std::string said = "drive = \"" + drive + "\"";
  if (!n) return said + " (the default)";
  return said + " (" + (cfg::from_option(*n) ? "--drive " + drive : cfg::where(*n)) + ")";
}
}  // namespace

std::string table_drive(const toml::table& t) {
  const std::string drive = cfg::get_string(t, "drive", std::string("rig-v1"));
  if (drive != "rig-v1" && drive != "cia402")
    throw ConfigError(cfg::where(*t.get("drive")) + ": [table] drive = \"" + drive +
                      "\": expected \"rig-v1\" (docs/table-registers.md) or \"cia402\" (docs/cia402-drive-maps.md)");
  if (drive == "cia402" && !t.contains("drive_map"))
    throw ConfigError(cfg::where(t) + ": [table] drive = \"cia402\" needs drive_map = \"FILE\" (see drives/)");
  if (drive == "rig-v1" && t.contains("drive_map"))
    throw ConfigError(cfg::where(*t.get("drive_map")) + ": drive_map is for drive = \"cia402\"");
  if (const toml::node* n = t.get("unacked_motion_s"); n && drive == "rig-v1")
    cfg::reject(*n, "unacked_motion_s",
                "is for drive = \"cia402\" (the set-point acknowledge, statusword bit 12); the rig-v1 map has none, "
                "and this table is " + drive_said(t, drive));
  if (drive == "cia402")
    for (const char* k : {"in_position_window_deg", "drive_settle_s"})
      if (const toml::node* n = t.get(k))
        cfg::reject(*n, k, "is a rig-v1 register; a CiA 402 drive keeps its own, and this table is " + drive_said(t, drive));
  return drive;
}

// A relative path is looked for beside the file that names it (a hardware file travels with its
// maps), then in the working folder (as before that rule; kept so old set-ups still run, but said:
// the travel limits then depend on where rig was started).
DriveMap table_drive_map(const toml::table& t) {
  const toml::node* n = t.get("drive_map");
  const std::string given = cfg::get_string(t, "drive_map");
  // "" is no file: named as what it is (it read "drive map '' not found: looked beside ...").
  if (given.empty()) throw ConfigError(cfg::where(*n) + ": drive_map is empty: name a drive map file (drives/*.toml)");
  const std::filesystem::path p = given;
  std::error_code ec;  // (a working folder removed under us: absolute() gives an empty path)
  const std::filesystem::path cwd = std::filesystem::absolute(p, ec);
  if (p.is_relative() && n->source().path) {
    const std::filesystem::path file(*n->source().path);
    const std::string beside_text = (file.parent_path() / p).string();
    if (path_kind(beside_text, "drive map") != PathKind::missing) return load_drive_map(beside_text);
    if (path_kind(p.string(), cfg::where(*n) + ": drive map") == PathKind::missing)
      throw ConfigError(cfg::where(*n) + ": drive map '" + given + "' not found: looked beside " + file.string() +
                        " (" + beside_text + "), then in the working folder (" + cwd.string() + ")");
    cfg::warn_once(cfg::where(*n) + ": drive map '" + given + "' is not beside " + file.string() +
                   "; taken from the working folder (" + cwd.string() +
                   "): its travel limits depend on where rig is started (put the map beside the hardware file)");
    return load_drive_map(p.string());
  }
  if (path_kind(p.string(), cfg::where(*n) + ": drive map") == PathKind::missing)
    throw ConfigError(cfg::where(*n) + ": drive map '" + given + "' not found" +
                      (p.is_relative() ? " in the working folder (" + cwd.string() + ")" : std::string()));
  return load_drive_map(p.string());
}

namespace {

struct TableConfig {
  Endpoint ep;
  LinkOptions link;
  TableOptions opt;
  std::optional<DriveMap> map;
};

// [table] velocity_dps / accel_dps2 in the drive map's units must fit the profile registers the
// rig writes them to: checked with the file, before the drive is opened (they were cut to their
// low 16 bits: 20 deg/s became a creep, 30 deg/s a 0 the drive refused, a review). They are sent
// as whole units: one that rounds to 0 is refused (the drive was told to stand still and the move
// timed out blaming the drive, a review), one rounded by more than kRoundingNote is said once.
constexpr double kRoundingNote = 0.01;

void check_profile_values(const toml::table& t, const DriveMap& map, const TableOptions& o) {
  auto check = [&](const char* key, const std::optional<double>& v, Obj ob, double units, const std::string& unit) {
    if (!v || !map.has(ob) || map.fits(ob, std::llround(units))) return;
    char b[160];
    std::snprintf(b, sizeof b, "[table] %s = %g is %.0f %s in the drive's units, which does not fit ", key, *v, units,
                  unit.c_str());
    throw ConfigError(cfg::where(*t.get(key)) + ": " + b + map.describe(ob) + ", " + map.range_text(ob) +
                      " (drive map " + map.path + ")");
  };
  // `back`: drive units to the key's unit (deg/s, deg/s^2).
  auto rounding = [&](const char* key, double v, double units, const char* unit, const char* key_unit, auto back) {
    const double sent = static_cast<double>(std::llround(units));
    const std::string at = cfg::where(*t.get(key));
    char b[320];
    if (sent == 0) {
      std::snprintf(b, sizeof b,
                    "[table] %s = %g is %.4g %s in the drive's units, which rounds to 0: sent as 0, the drive "
                    "would not move; the least it can be sent is 1 %s = %.4g %s (drive map %s)",
                    key, v, units, unit, unit, back(1.0), key_unit, map.path.c_str());
      throw ConfigError(at + ": " + b);
    }
    const double off = (sent - units) / units;
    if (std::fabs(off) <= kRoundingNote) return;
    std::snprintf(b, sizeof b, "[table] %s = %g is %.4g %s in the drive's units, sent as %.0f %s = %.4g %s (%.1f %% %s)",
                  key, v, units, unit, sent, unit, back(sent), key_unit, std::fabs(off) * 100,
                  off < 0 ? "less" : "more");
    cfg::warn_once(at + ": " + b);
  };
  // A speed the map has no object for is never sent: the drive moves at what it holds, and a
  // dry run said "as sent" (an integrator's review). Refused at its line, as an unsendable value is.
  auto unsendable = [&](const char* key, double v, const char* objects) {
    char b[400];
    std::snprintf(b, sizeof b,
                  "[table] %s = %g cannot be sent: drive map %s has no %s object, so the drive would move at the "
                  "value it holds; add the object to the map or leave %s out",
                  key, v, map.path.c_str(), objects, key);
    throw ConfigError(cfg::where(*t.get(key)) + ": " + b);
  };
  const std::string v_unit = map.velocity_unit_text(), a_unit = map.accel_unit_text();
  if (o.velocity_dps && !map.has(Obj::kProfileVelocity)) unsendable("velocity_dps", *o.velocity_dps, "profile_velocity (0x6081)");
  if (o.accel_dps2 && !map.has(Obj::kProfileAcceleration) && !map.has(Obj::kProfileDeceleration))
    unsendable("accel_dps2", *o.accel_dps2, "profile_acceleration (0x6083) or profile_deceleration (0x6084)");
  if (o.velocity_dps) {
    const double units = map.dps_to_velocity_units(*o.velocity_dps);
    check("velocity_dps", o.velocity_dps, Obj::kProfileVelocity, units, v_unit);
    if (map.has(Obj::kProfileVelocity))
      rounding("velocity_dps", *o.velocity_dps, units, v_unit.c_str(), "°/s",
               [&](double u) { return std::fabs(map.velocity_units_to_dps(u)); });
  }
  if (o.accel_dps2) {
    const double units = map.dps2_to_accel_units(*o.accel_dps2);
    for (const Obj ob : {Obj::kProfileAcceleration, Obj::kProfileDeceleration})
      check("accel_dps2", o.accel_dps2, ob, units, a_unit);
    if (map.has(Obj::kProfileAcceleration) || map.has(Obj::kProfileDeceleration))
      rounding("accel_dps2", *o.accel_dps2, units, a_unit.c_str(), "°/s²",
               [&](double u) { return map.accel_units_to_dps2(u); });
  }
}

std::string cfg_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// A tolerance below one position count can never be met by a drive at rest on a count (`0` was
// accepted, and no move ever completed: "stopped 0.0000° off target", a review).
void check_tolerance(const toml::table& t, const DriveMap* map, double tolerance_deg) {
  const double count_deg = map ? 1.0 / map->counts_per_deg() : 1.0 / kPosScale;
  if (tolerance_deg >= count_deg * (1 - 1e-9)) return;
  const double step = std::pow(10.0, std::floor(std::log10(count_deg)) - 2);  // 3 significant digits, up
  char b[400];
  std::snprintf(b, sizeof b, "below one position count of the drive (%.3g°, %s): no move could ever be confirmed in "
                "position; give at least %.3g", count_deg, map ? ("drive map " + map->path).c_str() : "rig-v1 register map",
                std::ceil(count_deg / step - 1e-6) * step);
  if (const toml::node* n = t.get("tolerance_deg")) cfg::reject(*n, "tolerance_deg", b);
  throw ConfigError(cfg::where(t) + ": [table] tolerance_deg (default " + cfg_number(tolerance_deg) + "°) is " + b);
}

// Everything [table] says, checked, without touching the drive.
TableConfig read_table_config(const toml::table& t) {
  cfg::check_keys(t,
                  {"modbus", "rtu", "unit", "response_timeout_s", "retries", "backoff_s", "tolerance_deg", "settle_s",
                   "poll_s", "move_timeout_s", "home_timeout_s", "ack_timeout_s", "heartbeat_timeout_s",
                   "ended_short_s", "unacked_motion_s",
                   "velocity_dps", "accel_dps2", "in_position_window_deg", "drive_settle_s", "u10_deg", "u20_deg",
                   "drive", "drive_map"},
                  "table");
  TableConfig c;
  if (table_drive(t) == "cia402") c.map = table_drive_map(t);
  const bool tcp = t.contains("modbus"), rtu = t.contains("rtu");
  if (tcp == rtu) throw ConfigError(cfg::where(t) + ": [table] needs exactly one of modbus = \"tcp:HOST:PORT\" or rtu = \"DEVICE,BAUD,P,8,1\"");
  try {
    c.ep = tcp ? parse_endpoint(cfg::get_string(t, "modbus")) : parse_rtu(cfg::get_string(t, "rtu"));
  } catch (const ConfigError& e) {
    throw ConfigError(cfg::where(*t.get(tcp ? "modbus" : "rtu")) + ": " + e.what());
  }
  // A client needs the drive's port: 0 ("any", a server's) failed later as "cannot connect" (a review).
  if (c.ep.kind == Endpoint::Kind::kTcp && c.ep.port == 0)
    cfg::reject(*t.get("modbus"), "modbus", "port 0 is no drive's port (1..65535)");
  c.opt = table_options_from_toml(t);
  c.link = link_options_from_toml(t);
  if (c.map) check_profile_values(t, *c.map, c.opt);
  check_tolerance(t, c.map ? &*c.map : nullptr, c.opt.tolerance_deg);
  // The procedure's angles, accepted here as in [procedure] (older files) and held to the same
  // rules, a CiA 402 map's travel included; the run's angles are [procedure]'s.
  for (const auto& [key, lo, hi] : {std::tuple{"u10_deg", -360.0, 360.0}, {"u20_deg", -360.0, 540.0}}) {
    const double deg = cfg::get_number(t, key, 0.0, lo, hi);
    if (c.map && t.contains(key) && (deg < c.map->limit_neg_deg || deg > c.map->limit_pos_deg))
      cfg::reject(*t.get(key), key,
                  "outside the table's travel [" + cfg_number(c.map->limit_neg_deg) + "°, " +
                      cfg_number(c.map->limit_pos_deg) + "°] (drive map " + c.map->path +
                      " [limits]); the run takes its angles from [procedure] u10_deg / u20_deg");
  }
  return c;
}

}  // namespace

void check_table_config(const toml::table& t) { read_table_config(t); }

namespace {
// One key for every spelling of a TCP host: of the addresses it resolves to, numeric, the least
// IPv4 one as text (else the least IPv6 one; an IPv4-mapped one as IPv4, the unspecified ones as
// the loopback): the same pick from the same set. The name in lower case where it does not resolve.
// "localhost", "LOCALHOST" and "127.0.0.1" were three keys, so two terminals could command one
// drive at once. A literal address resolves without a lookup.
std::string host_key(const std::string& host) {
  std::string lower = host;
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  if (::getaddrinfo(host.c_str(), nullptr, &hints, &res) != 0 || res == nullptr) return lower;
  std::optional<std::string> v4, v6;
  for (const addrinfo* a = res; a != nullptr; a = a->ai_next) {
    char buf[NI_MAXHOST];
    if (::getnameinfo(a->ai_addr, a->ai_addrlen, buf, sizeof buf, nullptr, 0, NI_NUMERICHOST) != 0) continue;
    std::string addr = buf;
    const bool mapped = addr.rfind("::ffff:", 0) == 0 && addr.find('.') != std::string::npos;
    if (mapped) addr.erase(0, 7);
    // The unspecified address is this host to connect(2) ("0.0.0.0" and "0" reached a drive held
    // under 127.0.0.1: a review), so it is keyed as the loopback.
    if (addr == "0.0.0.0") addr = "127.0.0.1";
    if (addr == "::") addr = "::1";
    std::optional<std::string>& least = a->ai_family == AF_INET || mapped ? v4 : v6;
    if (!least || addr < *least) least = addr;
  }
  ::freeaddrinfo(res);
  return v4 ? *v4 : v6 ? *v6 : lower;
}
}  // namespace

std::string table_identity(const toml::table& t) {
  const TableConfig c = read_table_config(t);
  if (c.ep.kind == Endpoint::Kind::kTcp) {
    Endpoint ep = c.ep;
    ep.host = host_key(ep.host);
    return ep.str() + " unit " + std::to_string(c.link.unit);
  }
  // A serial line is one bus whatever its settings or unit, and one device by any of its names
  // (/dev/serial/by-id/... links to /dev/ttyUSB0): two keys let a second process drive it (a review).
  std::error_code ec;
  const std::filesystem::path dev = std::filesystem::canonical(c.ep.device, ec);
  return "rtu:" + (ec ? c.ep.device : dev.string());
}

std::unique_ptr<RotaryTable> connect_table(const toml::table& t, Clock& clock) {
  TableConfig c = read_table_config(t);
  auto transport = make_libmodbus_transport(c.ep, c.link, clock);
  if (c.map) return std::make_unique<Cia402Table>(std::move(transport), std::move(*c.map), clock, c.opt);
  return std::make_unique<TableClient>(std::move(transport), clock, c.opt);
}

std::unique_ptr<RotaryTable> make_inprocess_table(RegisterDevice& dev, Clock& clock, TableOptions opt) {
  return std::make_unique<TableClient>(make_inprocess_transport(dev, clock), clock, std::move(opt));
}

}  // namespace rig::modbus
