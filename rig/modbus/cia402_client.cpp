#include "rig/modbus/cia402_client.hpp"
#include "rig/modbus/motion_text.hpp"
#include "rig/core/toml_util.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rig::modbus {

namespace c4 = cia402;
using c4::State;

namespace {

using detail::deg_str;
using detail::hex4;
using detail::deg_str_past;
using detail::secs;
using detail::TakenOverError;
using detail::trapezoid_time;

constexpr double kDefaultMoveTimeoutS = 120.0;  // when the profile velocity is unknown
constexpr double kRestTimeoutS = 30.0;          // a stopping axis must be at rest within this
constexpr double kRestDps = 0.01;               // velocity actual read as a servo holding position

}  // namespace

// A map without the device type is said once per file, by the client (the emulated drive that
// serves a map has nothing to tell apart): the client then tells the drive from a rig-v1 table by
// its statusword alone, and a rig-v1 table in motion reads like one of the standard's states
// (session 26's reviews).
Cia402Table::Cia402Table(std::unique_ptr<RegisterTransport> transport, DriveMap map, Clock& clock, TableOptions opt)
    : transport_(std::move(transport)), map_(std::move(map)), clock_(clock), opt_(std::move(opt)) {
  if (!map_.has(Obj::kDeviceType))
    cfg::warn_once("drive map " + map_.path +
                   ": no device_type (0x1000) in [objects]: the rig tells this drive from a rig-v1 table by its "
                   "statusword alone, which a rig-v1 table in motion can pass; if the drive serves 0x1000 on "
                   "Modbus, map it (device_type = { index = 0x1000, address = N, width = 32 }; "
                   "docs/cia402-drive-maps.md, \"Which device answers\")");
}

// At rest: velocity actual within 0.01 °/s. Where one unit of the velocity object is coarser, a
// servo holding position jitters by a unit (a review: rpm through a 100:1 gear is 0.06 °/s a
// unit, and such jitter blocked every move for 30 s as "still moving"): a reading within 1.5
// units is rest too when position actual also held within 2 counts since the previous reading,
// `prev`, taken at least a poll before. A single reading (a stop deciding whether to halt) has no
// such evidence and keeps the 0.01 °/s: 1.5 units is 9 °/s on a direct drive in rpm (a code review).
bool Cia402Table::reads_at_rest(const Cia402Reading& r, const Cia402Reading* prev) const {
  if (std::fabs(r.velocity_dps) <= kRestDps) return true;
  if (!prev || std::fabs(r.velocity_dps) > 1.5 * std::fabs(map_.velocity_units_to_dps(1.0))) return false;
  return std::fabs(r.actual_deg - prev->actual_deg) <= std::fabs(map_.counts_to_deg(2) - map_.counts_to_deg(0));
}

std::string Cia402Table::describe() const { return transport_->describe() + " cia402 \"" + map_.name + "\""; }

// One object, named with its register and the drive when the link fails.
int64_t Cia402Table::read_object(Obj o, const CancelToken& cancel, bool urgent) {
  const ObjectSpec& s = map_.spec(o);
  try {
    const auto w = s.input ? transport_->read_input(s.address, static_cast<uint16_t>(s.words()), cancel, urgent)
                           : transport_->read(s.address, static_cast<uint16_t>(s.words()), cancel, urgent);
    return map_.decode(o, w.data());
  } catch (const ModbusError& e) {
    // Another protocol answering before the drive was known (an HTTP server at the port): no drive,
    // nothing sent (as TableClient::read_drive says it).
    if (e.foreign_reply && !identified_)
      throw detail::NotThisDriveError("reading " + map_.describe(o) + " of drive \"" + map_.name + "\": " + e.what() +
                                      " (" + kForeignPeer + "); nothing sent");
    throw ModbusError("reading " + map_.describe(o) + " of drive \"" + map_.name + "\": " + e.what(), e.exception_code,
                      e.timeout, e.foreign_reply);
  }
}

void Cia402Table::write_object(Obj o, int64_t value, const CancelToken& cancel, bool urgent) {
  try {
    transport_->write(map_.spec(o).address, map_.encode(o, value), cancel, urgent);
  } catch (const ModbusError& e) {
    throw ModbusError("writing " + map_.describe(o) + " of drive \"" + map_.name + "\": " + e.what(), e.exception_code,
                      e.timeout, e.foreign_reply);
  }
}

// Within a move or homing run, never over a stop asked meanwhile (StopLatch).
void Cia402Table::write_controlword(uint16_t w, const CancelToken& cancel) {
  stops_.write_command(w, cancel, [&] {
    write_object(Obj::kControlword, w, cancel);
    control_ = w;
    control_known_ = true;
    control_written_ = true;
  });
}

// Reads the objects of one poll, contiguous registers of one function in one request.
Cia402Reading Cia402Table::read(const CancelToken& cancel, bool commands) {
  const Obj want[] = {Obj::kStatusword, Obj::kErrorCode, Obj::kModesDisplay, Obj::kPositionActual,
                      Obj::kVelocityActual};
  std::vector<Obj> objs(std::begin(want), std::end(want));
  if (commands) objs.insert(objs.end(), {Obj::kControlword, Obj::kTargetPosition});
  // The statusword's register kind first: a silent drive is named by the statusword's read.
  const bool first_kind = map_.spec(Obj::kStatusword).input;
  std::sort(objs.begin(), objs.end(), [&](Obj a, Obj b) {
    const auto &sa = map_.spec(a), &sb = map_.spec(b);
    return sa.input != sb.input ? sa.input == first_kind : sa.address < sb.address;
  });
  std::array<int64_t, kObjCount> val{};
  for (size_t i = 0; i < objs.size();) {
    size_t j = i + 1;
    uint32_t end = map_.spec(objs[i]).address + map_.spec(objs[i]).words();
    while (j < objs.size() && map_.spec(objs[j]).input == map_.spec(objs[i]).input &&
           map_.spec(objs[j]).address == end && end + map_.spec(objs[j]).words() - map_.spec(objs[i]).address <= 125) {
      end += map_.spec(objs[j]).words();
      ++j;
    }
    const ObjectSpec& first = map_.spec(objs[i]);
    const auto n = static_cast<uint16_t>(end - first.address);
    std::vector<uint16_t> w;
    try {
      w = first.input ? transport_->read_input(first.address, n, cancel) : transport_->read(first.address, n, cancel);
    } catch (const ModbusError& e) {
      std::string names;
      for (size_t k = i; k < j; ++k) names += (k > i ? ", " : "") + map_.describe(objs[k]);
      if (e.foreign_reply && !identified_)  // as read_object says it
        throw detail::NotThisDriveError("reading " + names + " of drive \"" + map_.name + "\": " + e.what() + " (" +
                                        kForeignPeer + "); nothing sent");
      throw ModbusError("reading " + names + " of drive \"" + map_.name + "\": " + e.what(), e.exception_code,
                        e.timeout, e.foreign_reply);
    }
    for (size_t k = i; k < j; ++k)
      val[static_cast<int>(objs[k])] = map_.decode(objs[k], w.data() + (map_.spec(objs[k]).address - first.address));
    i = j;
  }
  Cia402Reading r;
  r.statusword = static_cast<uint16_t>(val[static_cast<int>(Obj::kStatusword)]);
  r.error_code = static_cast<uint16_t>(val[static_cast<int>(Obj::kErrorCode)]);
  r.mode_display = static_cast<int8_t>(val[static_cast<int>(Obj::kModesDisplay)]);
  r.actual_deg = map_.counts_to_deg(val[static_cast<int>(Obj::kPositionActual)]);
  r.velocity_dps = map_.velocity_units_to_dps(static_cast<double>(val[static_cast<int>(Obj::kVelocityActual)]));
  if (commands) {
    r.controlword = static_cast<uint16_t>(val[static_cast<int>(Obj::kControlword)]);
    r.target_counts = val[static_cast<int>(Obj::kTargetPosition)];
  }
  if (!identified_) identify(r, cancel);
  angle_seen(r.actual_deg);
  return r;
}

namespace {
const char* const kWhichDrive =
    "if it is a rig-v1 table give --drive rig-v1 (drive = \"rig-v1\" in the hardware file's [table]); otherwise "
    "check the drive map's addresses against the drive's manual";
}  // namespace

// Why this device is not the drive the map describes ("" when it is): a statusword that is none
// of the standard's eight states, or (when the map has it) a device type (0x1000) that is not
// profile 402 or that the device refuses (exception 02: no such register). Other read failures
// (a timeout) are thrown: they say nothing about the device.
std::string Cia402Table::identity_problem(uint16_t statusword, const CancelToken& cancel, bool urgent, bool* is_402) {
  if (!c4::is_state(statusword))
    return map_.describe(Obj::kStatusword) + " reads " + hex4(statusword) +
           ", which is none of the CiA 402 states (IEC 61800-7-201): not a CiA 402 drive (a rig-v1 table reads like "
           "this), or the map's statusword address is wrong";
  if (!map_.has(Obj::kDeviceType)) return "";
  int64_t type = 0;
  try {
    type = read_object(Obj::kDeviceType, cancel, urgent);
  } catch (const ModbusError& e) {
    if (e.exception_code != exc::kIllegalAddress) throw;
    return map_.describe(Obj::kDeviceType) + " does not exist on the device (exception 0x02): not a CiA 402 drive, "
           "or the map's address is wrong";
  }
  if ((type & 0xFFFF) == c4::kDeviceProfile) return "";
  char b[16];
  std::snprintf(b, sizeof b, "0x%0*llX", map_.spec(Obj::kDeviceType).width / 4, static_cast<unsigned long long>(type));
  // 0x0192 in the high word of a 32-bit read: the drive's words in the other order (a review).
  const bool swapped = map_.spec(Obj::kDeviceType).width == 32 && ((type >> 16) & 0xFFFF) == c4::kDeviceProfile;
  if (is_402) *is_402 = swapped;
  return map_.describe(Obj::kDeviceType) + " reads " + b + ", not device profile 402 (0x0192) in its low word: " +
         (swapped ? "0x0192 is in its high word, so the drive sends 32-bit values in the other word order than the "
                    "map's word_order says (high_first / low_first)"
                  : "not a CiA 402 drive, or the map's address is wrong");
}

// A homed table reads inside its travel. One that reads outside it is read wrong: a map whose
// word order is the drive's reversed read 580.78° on a [-10°, 350°] table, and its move to 20°
// went to 204.78° at the drive's top speed, reported done (a review). Refused before anything is
// written; a table truly past a limit is moved off it with the drive's own tools.
void Cia402Table::refuse_outside_travel(const std::string& doing, const Cia402Reading& r) const {
  constexpr double kMarginDeg = 1.0;  // a table stopped just past a limit by its deceleration
  if (r.actual_deg >= map_.limit_neg_deg - kMarginDeg && r.actual_deg <= map_.limit_pos_deg + kMarginDeg) return;
  throw HardwareError(doing + ": position actual reads " + deg_str(r.actual_deg) + ", outside the travel [limits] [" +
                      deg_str(map_.limit_neg_deg) + ", " + deg_str(map_.limit_pos_deg) + "] of drive map " + map_.path +
                      ": the map does not read this drive as it is (check word_order, counts_per_rev, gear_ratio, "
                      "direction and the home offset against the drive's manual), or the table was not homed "
                      "(`rig table home` brings a table read right back into its travel); nothing sent");
}

// The first reading of a client, before it writes anything. A review found a CiA 402 client at a
// rig-v1 table reading "actual 300°, Not ready to switch on" without error; its quick stop
// (controlword 0x0002) or halt (0x0100) wrote that table's START or HALT with SERVO_ON clear, which
// dropped its servo.
void Cia402Table::identify(const Cia402Reading& r, const CancelToken& cancel) {
  bool is_402 = false;
  const std::string why = identity_problem(r.statusword, cancel, false, &is_402);
  // A reversed word order is this drive, misread: the advice to check `drive` would contradict it.
  if (!why.empty())
    throw detail::NotThisDriveError(describe() + ": " + why + (is_402 ? std::string() : " (" + std::string(kWhichDrive) + ")") +
                                    "; nothing sent");
  identified_ = true;
}

TableStatus Cia402Table::status() {
  Cia402Reading r;
  double target = 0;  // the drive's target position object (0x607A, required in every map)
  try {
    r = read();
    // The controlword as the drive holds it: a stop from a fresh process
    // (`rig table stop`) then keeps its device control bits.
    control_ = static_cast<uint16_t>(read_object(Obj::kControlword, {}));
    control_known_ = true;
    target = map_.counts_to_deg(read_object(Obj::kTargetPosition, {}));
  } catch (const ModbusError& e) {
    throw HardwareError(std::string("table status: ") + e.what());
  }
  TableStatus s;
  const State st = r.state();
  s.actual_deg = r.actual_deg;
  s.ready = st != State::kFault && st != State::kFaultReactionActive && st != State::kNotReadyToSwitchOn;
  s.servo_on = st == State::kOperationEnabled || st == State::kQuickStopActive;
  s.homed = map_.homed_bit ? r.has(static_cast<uint16_t>(1u << *map_.homed_bit)) : homed_;
  s.homed_known = map_.homed_bit.has_value() || homed_;
  s.homing = r.mode_display == c4::kModeHoming && s.servo_on && !r.has(c4::sw::kTargetReached);
  // Velocity actual within 0.01 °/s is a servo holding position, not motion (one reading: no
  // evidence from the position, so no allowance for a coarse unit's jitter).
  s.moving = !reads_at_rest(r, nullptr) || (s.servo_on && !r.has(c4::sw::kTargetReached));
  s.in_position = s.servo_on && r.has(c4::sw::kTargetReached) && !s.moving;
  s.alarm = st == State::kFault || st == State::kFaultReactionActive;
  s.alarm_code = r.error_code;
  s.alarm_text = r.error_code ? c4::error_code_text(r.error_code) : "";
  s.target_deg = target;  // as the drive holds it (it was shown as the actual angle: a review)
  s.has_heartbeat = false;
  s.drive_state = c4::state_name(st);  // e.g. "Quick stop active", which the flags do not show
  return s;
}

std::string Cia402Table::at(const Cia402Reading& r) const {
  // A word that is none of the states is not named as one (0xFFFF read "Not ready to switch on",
  // the decoder's fallback, a review).
  return " at " + deg_str(r.actual_deg) + " (" +
         (c4::is_state(r.statusword) ? c4::state_name(r.state()) : std::string("none of the CiA 402 states")) +
         ", statusword " + hex4(r.statusword) + ")";
}

void Cia402Table::fail_on_fault(const std::string& doing, const Cia402Reading& r, const char* after) const {
  const State st = r.state();
  if (st != State::kFault && st != State::kFaultReactionActive) return;
  // A fault with no error code is what a statusword read from the wrong register looks like (a
  // review: a map with statusword and controlword swapped read "Fault reaction active, alarm none").
  throw HardwareError(doing + ": drive \"" + map_.name + "\" in " + c4::state_name(st) + ", error code " +
                      hex4(r.error_code) + " (0x603F) " + c4::error_code_text(r.error_code) + at(r) +
                      " (inspect the table, then `rig table reset`" +
                      (r.error_code == 0 ? "; with no error code, check the map's statusword address too: " +
                                               map_.describe(Obj::kStatusword)
                                         : std::string()) +
                      ")" + after);
}

// Waits (bounded by the acknowledge timeout) for the state a command leads to;
// any other state is reported, never worked around.
Cia402Reading Cia402Table::await_state(const std::string& doing, const char* command, State want,
                                       const CancelToken& cancel) {
  const double t0 = clock_.now_s();
  for (;;) {
    const Cia402Reading r = read(cancel);
    if (r.state() == want) return r;
    fail_on_fault(doing, r);
    if (clock_.now_s() - t0 > opt_.ack_timeout_s)
      throw HardwareError(doing + ": drive \"" + map_.name + "\" did not reach " + c4::state_name(want) + " within " +
                          secs(opt_.ack_timeout_s) + " of \"" + command + "\"" + at(r));
    clock_.sleep_for(opt_.poll_s, cancel);
  }
}

// Shutdown, switch on, enable operation (transitions 2, 3, 4), from wherever
// the standard leaves a defined way; Fault needs a technician's reset.
void Cia402Table::enable_operation(const std::string& doing, const CancelToken& cancel) {
  Cia402Reading r = read(cancel);
  const double t0 = clock_.now_s();
  while (r.state() == State::kNotReadyToSwitchOn) {  // drive still initialising (transition 1 is the drive's)
    if (clock_.now_s() - t0 > opt_.ack_timeout_s) {
      const uint16_t s = r.statusword;
      throw HardwareError(doing + ": drive \"" + map_.name + "\" stays Not ready to switch on (statusword " + hex4(s) +
                          ": not a state it should keep; refusing to guess)");
    }
    clock_.sleep_for(opt_.poll_s, cancel);
    r = read(cancel);
  }
  fail_on_fault(doing, r);
  for (int step = 0; step < 6; ++step) {
    switch (r.state()) {
      case State::kOperationEnabled: return;
      case State::kQuickStopActive: {  // after our quick stop: Disable voltage (transition 12), then up again
        // Not while the quick-stop ramp still runs: disabling would drop the axis on its brake.
        const double t_rest = clock_.now_s();
        for (std::optional<Cia402Reading> prev; !reads_at_rest(r, prev ? &*prev : nullptr);) {
          if (clock_.now_s() - t_rest > kRestTimeoutS)
            throw HardwareError(doing + ": still moving " + secs(kRestTimeoutS) + " after a quick stop" + at(r));
          clock_.sleep_for(opt_.poll_s, cancel);
          prev = r;
          r = read(cancel);
        }
        write_controlword(c4::cw::kDisableVoltage, cancel);
        r = await_state(doing, "disable voltage", State::kSwitchOnDisabled, cancel);
        break;
      }
      case State::kSwitchOnDisabled:
        write_controlword(c4::cw::kShutdown, cancel);
        r = await_state(doing, "shutdown", State::kReadyToSwitchOn, cancel);
        break;
      case State::kReadyToSwitchOn:
        write_controlword(c4::cw::kCmdSwitchOn, cancel);
        r = await_state(doing, "switch on", State::kSwitchedOn, cancel);
        break;
      case State::kSwitchedOn:
        write_controlword(c4::cw::kCmdEnableOperation, cancel);
        r = await_state(doing, "enable operation", State::kOperationEnabled, cancel);
        break;
      default:
        fail_on_fault(doing, r);
        throw HardwareError(doing + ": drive \"" + map_.name + "\" in an unexpected state" + at(r) +
                            "; refusing to guess");
    }
  }
  throw HardwareError(doing + ": drive \"" + map_.name + "\" did not settle in Operation enabled" + at(r));
}

// A table still moving (another master's move, a halt's ramp) comes to rest before this client
// writes a mode or set-point, as the rig-v1 client waits: a second `rig table move` took the
// first one's axis mid-move. Bounded, so a runaway is reported.
void Cia402Table::wait_at_rest(const std::string& doing, const CancelToken& cancel) {
  const double t0 = clock_.now_s();
  std::optional<Cia402Reading> prev;
  for (Cia402Reading r = read(cancel); !reads_at_rest(r, prev ? &*prev : nullptr); r = read(cancel)) {
    fail_on_fault(doing, r);
    if (clock_.now_s() - t0 > kRestTimeoutS)
      throw HardwareError(doing + ": the table is still moving after " + secs(kRestTimeoutS) +
                          " (another Modbus master?)" + at(r));
    clock_.sleep_for(opt_.poll_s, cancel);
    prev = r;
  }
}

void Cia402Table::set_mode(const std::string& doing, int mode, const CancelToken& cancel) {
  write_object(Obj::kModesOfOperation, mode, cancel);
  const double t0 = clock_.now_s();
  for (;;) {
    const Cia402Reading r = read(cancel);
    fail_on_fault(doing, r);
    if (r.mode_display == mode) return;
    if (clock_.now_s() - t0 > opt_.ack_timeout_s)
      throw HardwareError(doing + ": modes of operation display (0x6061) shows " + std::to_string(r.mode_display) +
                          ", not " + std::to_string(mode) + ", " + secs(opt_.ack_timeout_s) + " after writing 0x6060" +
                          at(r));
    clock_.sleep_for(opt_.poll_s, cancel);
  }
}

template <class Body>
void Cia402Table::guarded(const std::string& doing, Body body) {
  detail::guarded_call(
      doing, body, [] { return std::string(); },
      [this] { return stops_.send_again([this] { quick_stop(); }, [this] { stop(); }); },
      [this] { return last_stop_error(); });
}

void Cia402Table::home(const CancelToken& cancel) {
  const std::string doing = "home";
  const detail::StopLatch::Scope operation(stops_, doing);
  guarded(doing, [&] {
    enable_operation(doing, cancel);
    wait_at_rest(doing, cancel);
    set_mode(doing, c4::kModeHoming, cancel);
    if (map_.homing_method != 0) write_object(Obj::kHomingMethod, map_.homing_method, cancel);
    if (map_.has(Obj::kHomeOffset)) write_object(Obj::kHomeOffset, map_.deg_to_counts(map_.home_offset_deg), cancel);
    write_controlword(c4::cw::kCmdEnableOperation, cancel);
    homed_ = false;  // a homing run started loses the reference until it is attained
    write_controlword(c4::cw::kCmdEnableOperation | c4::cw::kHomingStart, cancel);
    const double t0 = clock_.now_s();
    double changed_at = t0;
    Cia402Reading last = read(cancel);
    Cia402Reading end;  // the reading that said attained
    bool seen_running = false;  // target reached clear once: the drive took the homing start
    detail::HeldFor interrupted;  // bits 13, 12, 10 read 0, 0, 1 after that
    for (;;) {
      clock_.sleep_for(opt_.poll_s, cancel);
      const Cia402Reading r = read(cancel, true);
      fail_on_fault(doing, r);
      // Another master's halt or mode, a quick stop: at once, by name; they read as a frozen
      // drive after heartbeat_timeout_s before (a review, on the rig-v1 client's homing).
      fail_on_halt(doing, r, "during homing");
      fail_unless_mode(doing, r, "during homing", c4::kModeHoming);
      if (r.has(c4::sw::kHomingError)) throw HardwareError(doing + ": homing error (statusword bit 13)" + at(r));
      const bool done = r.has(c4::sw::kHomingAttained) && r.has(c4::sw::kTargetReached);
      if (done) {
        end = r;
        break;
      }
      // Bits 13, 12, 10 = 0, 0, 1: "homing procedure is interrupted or not started" (CiA 402 /
      // IEC 61800-7-201, homing mode statusword); after the run was seen, interrupted: by a halt
      // released again, which leaves nothing to read back. Held ended_short_s first: a drive
      // may set bit 10 some cycles before bit 12 at the end of a good run, or dwell at a switch
      // (a review: 15 ms between them failed a good run when taken on two polls). Meanwhile the
      // table is at rest, not frozen. The halt follows as for any fault: a vendor's homing that
      // dwells longer with bit 10 set moved on after the rig had given up on it (a review).
      const double now = clock_.now_s();
      seen_running = seen_running || !r.has(c4::sw::kTargetReached);
      const double interrupted_s = interrupted(seen_running && r.has(c4::sw::kTargetReached), now);
      if (interrupted_s >= opt_.ended_short_s)
        throw HardwareError(doing + ": homing interrupted before the home was attained (statusword bit 10 set, bit 12 "
                                    "clear for " + secs(interrupted_s) + "; stopped by another Modbus master?)" + at(r));
      if (interrupted_s >= 0) changed_at = now;  // at rest by the drive's own account
      if (r.statusword != last.statusword || std::fabs(r.actual_deg - last.actual_deg) > 1e-9) changed_at = now;
      last = r;
      if (now - changed_at > opt_.heartbeat_timeout_s) {
        // Bits 13, 12, 10 = 0, 0, 1 since the start, the run never seen: "not started" in the
        // standard's words (a halt set and released before the first poll leaves this too).
        if (!seen_running && r.has(c4::sw::kTargetReached))
          throw HardwareError(doing + ": homing not started: statusword bit 10 set, bit 12 clear (\"interrupted or not "
                                      "started\") and nothing changed for " + secs(now - changed_at) +
                              " after the homing start (stopped by another Modbus master?)" + at(r));
        throw HardwareError(doing + ": drive frozen: statusword and position actual unchanged for " +
                            secs(now - changed_at) + " while homing" + at(r));
      }
      if (now - t0 > opt_.home_timeout_s) throw HardwareError(doing + ": not homed after " + secs(now - t0) + at(r));
    }
    write_controlword(c4::cw::kCmdEnableOperation, cancel);
    // A vendor's homed bit may follow bit 12 by a cycle: read once more before it is refused.
    if (map_.homed_bit && !end.has(static_cast<uint16_t>(1u << *map_.homed_bit))) {
      clock_.sleep_for(opt_.poll_s, cancel);
      end = read(cancel, true);
    }
    refuse_misread_home(doing, end);
    homed_ = true;
  });
}

// Attained by the standard's bits, the home is then read as the map reads it. A map whose
// homed_bit the drive never sets, or whose word order is the drive's reversed (actual 6553.80°
// on a [-10°, 200°] table), ended "homed", exit 0, and every move after it was refused with
// advice to home again (an integrator's review). The table is at rest at its home either way.
void Cia402Table::refuse_misread_home(const std::string& doing, const Cia402Reading& r) const {
  const std::string check = " of drive map " + map_.path + " against the drive's manual";
  if (map_.homed_bit && !r.has(static_cast<uint16_t>(1u << *map_.homed_bit)))
    throw HardwareError(doing + ": the drive reports the home attained (statusword bits 12 and 10), but the map's "
                                "homed_bit " + std::to_string(*map_.homed_bit) + " reads 0" + at(r) +
                        ": check homed_bit" + check + " (CiA 402 names no homed bit; vendors place it)");
  // A home at a travel end (a limit switch's method, 1/2/17/18) may stop past it by its braking:
  // a tenth of the travel is room for that, and a misread map is off by far more (8192°, 6553.8°).
  const double margin_deg = std::max(1.0, 0.1 * (map_.limit_pos_deg - map_.limit_neg_deg));
  if (r.actual_deg < map_.limit_neg_deg - margin_deg || r.actual_deg > map_.limit_pos_deg + margin_deg)
    throw HardwareError(doing + ": the drive reports the home attained, but position actual reads " +
                        deg_str(r.actual_deg) + ", outside the travel [" + deg_str(map_.limit_neg_deg) + ", " +
                        deg_str(map_.limit_pos_deg) + "] by more than " + deg_str(margin_deg) + " (home offset " +
                        deg_str(map_.home_offset_deg) +
                        "): the map does not read this drive as it is; check word_order, counts_per_rev, gear_ratio "
                        "and direction" + check);
}

// What ends a profile-position move other than the drive's fault: stop() from another thread set
// halt, another master's set-point, halt or mode (TakenOverError: no
// halt of ours over its motion, as the rig-v1 client on its target register), the drive left
// Operation enabled (quick stop, an external disable) or restarted. Another master's set-point or
// halt went unnoticed: the move waited out its timeout, then halted whatever the table then did (a
// review). `target_counts`: the set-point this client wrote.
void Cia402Table::fail_unless_moving(const std::string& doing, const Cia402Reading& r, const char* when,
                                     int64_t target_counts) const {
  fail_on_halt(doing, r, when);
  const bool restarted = drive_restarted(r);
  if (!restarted && r.target_counts && *r.target_counts != target_counts)
    throw TakenOverError(doing + ": target position (0x607A) changed to " +
                         deg_str(map_.counts_to_deg(*r.target_counts)) + " " + when + " (another Modbus master?)" +
                         at(r));
  fail_unless_mode(doing, r, when, c4::kModeProfilePosition);
}

// A drive that powers up again mid-move comes back in Switch on disabled (or not ready) with its
// power-on mode and target: say so, rather than blame another master.
bool Cia402Table::drive_restarted(const Cia402Reading& r) {
  const State st = r.state();
  return st == State::kSwitchOnDisabled || st == State::kNotReadyToSwitchOn;
}

// A stop asked of this client since the operation began (stop() or quick_stop() from another
// thread, sent or not: StopLatch), or a halt by another master, whose halt bit the controlword
// shows as read back (a gateway may read it as 0, which shows no halt).
void Cia402Table::fail_on_halt(const std::string& doing, const Cia402Reading& r, const char* when) const {
  if (stops_.since_begin()) throw HardwareError(doing + ": " + stops_.halted_by() + " " + when + at(r));
  if (!drive_restarted(r) && r.controlword && (*r.controlword & c4::cw::kHalt))
    throw TakenOverError(doing + ": halted by another master (controlword reads " + hex4(*r.controlword) + ") " +
                         when + at(r));
}

// The mode this client set, in Operation enabled; what else it reads, with its likely cause.
void Cia402Table::fail_unless_mode(const std::string& doing, const Cia402Reading& r, const char* when,
                                   int8_t mode) const {
  const State st = r.state();
  const bool restarted = drive_restarted(r);
  if (r.mode_display != mode) {
    if (restarted)
      throw HardwareError(doing + ": mode changed to " + std::to_string(r.mode_display) + " " + when +
                          " and the drive is in " + c4::state_name(st) + " (the drive restarted or was power-cycled?)" +
                          at(r));
    throw TakenOverError(doing + ": mode changed to " + std::to_string(r.mode_display) + " " + when +
                         " (another Modbus master?)" + at(r));
  }
  if (st != State::kOperationEnabled) {
    // Another master's command, where the read-back shows one that is not ours (0: a gateway's):
    // no halt of ours over it (a review: a quick stop from another shell got 0x0102 written over
    // its 0x0002), as on the rig-v1 map.
    const bool other = r.controlword && *r.controlword != 0 && *r.controlword != control_.load();
    if (other)
      throw TakenOverError(doing + ": drive left Operation enabled " + when + " (controlword reads " +
                           hex4(*r.controlword) + ": another Modbus master?)" + at(r));
    throw HardwareError(doing + ": drive left Operation enabled " + when + at(r));
  }
}

void Cia402Table::move_to(double deg, const CancelToken& cancel) {
  const std::string doing = "move to " + deg_str(deg);
  const detail::StopLatch::Scope operation(stops_, doing);
  if (!std::isfinite(deg) || deg < map_.limit_neg_deg || deg > map_.limit_pos_deg)
    throw ConfigError("move to " + deg_str_past(deg, deg < map_.limit_neg_deg ? map_.limit_neg_deg : map_.limit_pos_deg) +
                      ": outside the travel limits [" + deg_str(map_.limit_neg_deg) + ", " + deg_str(map_.limit_pos_deg) +
                      "] of drive map " + map_.path + "; nothing sent");
  // An unhomed table is refused before anything is written: enabling operation first left the
  // drive in Operation enabled after the refusal (a review).
  {
    const Cia402Reading r = detail::read_before_motion([&] { return read(cancel); },
                                                       [&](auto body) { guarded(doing, body); });
    // A fault first: "not homed" sent a technician to homing, which then failed on the fault (a
    // review). Nothing is written yet, and the message says so (a fuzz run: a drive in Fault
    // reaction active refused the move without a word on the halt, which it is not owed).
    fail_on_fault(doing, r, "; nothing sent");
    if (map_.homed_bit && !r.has(static_cast<uint16_t>(1u << *map_.homed_bit)))
      throw NotReadyError(doing + ": table not homed (run `rig table home` first)" + at(r) + "; nothing sent");
    refuse_outside_travel(doing, r);
  }
  guarded(doing, [&] {
    enable_operation(doing, cancel);
    wait_at_rest(doing, cancel);
    if (map_.homed_bit && !read(cancel).has(static_cast<uint16_t>(1u << *map_.homed_bit)))
      throw NotReadyError(doing + ": table not homed (run `rig table home` first)");
    set_mode(doing, c4::kModeProfilePosition, cancel);
    if (!profile_applied_) {
      auto setting = [&](Obj o, int64_t units, const char* key, double value) {
        detail::write_setting(opt_.where(key), key, value, [&] { write_object(o, units, cancel); });
      };
      if (opt_.velocity_dps && map_.has(Obj::kProfileVelocity))
        setting(Obj::kProfileVelocity, std::llround(map_.dps_to_velocity_units(*opt_.velocity_dps)), "velocity_dps",
                *opt_.velocity_dps);
      if (opt_.accel_dps2) {
        const auto a = std::llround(map_.dps2_to_accel_units(*opt_.accel_dps2));
        if (map_.has(Obj::kProfileAcceleration)) setting(Obj::kProfileAcceleration, a, "accel_dps2", *opt_.accel_dps2);
        if (map_.has(Obj::kProfileDeceleration)) setting(Obj::kProfileDeceleration, a, "accel_dps2", *opt_.accel_dps2);
      }
      profile_applied_ = true;
    }
    // Handshake (single set-point): new-set-point low and acknowledge clear first, with halt
    // (bit 8) set. Halt = 0 means "positioning shall be executed or continued" (IEC 61800-7-201,
    // profile position): a drive whose last move a halt interrupted (the rig's own stop, another
    // master's) goes on to that old target once halt clears. So halt clears only in the word
    // that brings this set-point, with "change set immediately" (bit 5): the drive takes it in
    // place of the old one, from rest (the table is at rest here). Clearing halt first sent a
    // standard drive towards the old target, and the set-point then waited for that move's end.
    write_controlword(c4::cw::kCmdEnableOperation | c4::cw::kHalt, cancel);
    Cia402Reading r = read(cancel);
    for (const double t_ack = clock_.now_s(); r.has(c4::sw::kSetPointAck);) {
      if (clock_.now_s() - t_ack > opt_.ack_timeout_s)
        throw HardwareError(doing + ": set-point acknowledge (bit 12) still set " + secs(opt_.ack_timeout_s) +
                            " after new-set-point was cleared" + at(r));
      clock_.sleep_for(opt_.poll_s, cancel);
      r = read(cancel);
    }
    const double start_deg = r.actual_deg;
    // The profile velocity the drive holds, read back on every move (a vendor tool may have
    // changed it; velocity_dps is not sent to a map without profile_velocity, a code review):
    // the fastest the table can turn. Unknown (0) where the map cannot read it: no pace check.
    const double v_drive =
        map_.has(Obj::kProfileVelocity)
            ? std::fabs(map_.velocity_units_to_dps(static_cast<double>(read_object(Obj::kProfileVelocity, cancel))))
            : 0.0;
    // A position that changes faster than that, twice over plus a degree, is read wrong (a word
    // order the drive's reversed reads 65536 counts per count; a review's table went to 204.78°
    // for a move to 20°, reported done). Each interval runs from before the earlier reading's
    // request to after the later one's reply, so a late reply never shortens it (a code review:
    // one reply 0.1 s late halted a good move); and the whole move is held to it from the set-point.
    const double t_cmd = clock_.now_s();
    double paced_deg = start_deg, paced_from = t_cmd;
    const auto check_pace = [&](const Cia402Reading& now_r, double asked_at, double answered_at) {
      const auto fast = [&](double moved, double in_s) { return v_drive > 0 && moved > 2 * v_drive * in_s + 1.0; };
      const double jump = std::fabs(now_r.actual_deg - paced_deg), since = answered_at - paced_from;
      const double all = std::fabs(now_r.actual_deg - start_deg), since_cmd = answered_at - t_cmd;
      if (fast(jump, since) || fast(all, since_cmd))
        throw HardwareError(doing + ": position actual " + (fast(jump, since) ? "jumped " + deg_str(jump) + " in " + secs(since)
                                                                            : "moved " + deg_str(all) + " in " + secs(since_cmd)) +
                            ", faster than the profile velocity " + deg_str(v_drive) + "/s (" +
                            map_.describe(Obj::kProfileVelocity) + ") lets the table turn: the map does not read this "
                            "drive's position or speed as it is (check word_order, counts_per_rev, gear_ratio, velocity_unit "
                            "and velocity_resolution against the drive's manual)" + at(now_r));
      paced_deg = now_r.actual_deg, paced_from = asked_at;
    };
    const int64_t target_counts = map_.deg_to_counts(deg);
    write_object(Obj::kTargetPosition, target_counts, cancel);
    write_controlword(c4::cw::kCmdEnableOperation | c4::cw::kNewSetPoint | c4::cw::kChangeImmediately, cancel);
    double t0 = clock_.now_s();
    detail::HeldFor unacked_motion;  // the table moving without the acknowledge
    Cia402Reading ack_prev = r;      // the reading a poll before (the one before the set-point first)
    for (;; ack_prev = r) {
      const double asked_at = clock_.now_s();
      r = read(cancel, true);
      fail_on_fault(doing, r);
      // Before the timeout's "not acknowledged": a drive that left Operation enabled or a stop
      // request never acknowledges, and the reason is that, not the drive.
      fail_unless_moving(doing, r, "waiting for the set-point acknowledge", target_counts);
      check_pace(r, asked_at, clock_.now_s());
      if (r.has(c4::sw::kSetPointAck)) break;
      // The table was at rest, and this word released halt: motion without the acknowledge is
      // the drive continuing a move a halt interrupted, to its old target (the set-point refused:
      // outside the drive's own limits, "change set immediately" not supported), or another
      // master's move started as ours was written. Halted either way once it has held
      // unacked_motion_s (0.1 s unless the hardware file says otherwise; a
      // poll may read the statusword just before the drive took the set-point, and a drive may set
      // bit 12 some cycles after its motion starts). Taken before for another master's move after
      // ack_timeout_s, with no halt, it let the table run on to the old target unwatched (a review).
      if (unacked_motion(!reads_at_rest(r, &ack_prev), clock_.now_s()) >= opt_.unacked_motion_s)
        throw HardwareError(doing + ": the table moves but the set-point is not acknowledged (statusword bit 12 clear): "
                                    "the drive continuing a halted move to its old target, or another master's move?" +
                            at(r));
      if (clock_.now_s() - t0 > opt_.ack_timeout_s)
        throw HardwareError(doing + ": set-point not acknowledged (statusword bit 12) within " +
                            secs(opt_.ack_timeout_s) + (r.has(c4::sw::kInternalLimit) ? " (internal limit active)" : "") +
                            at(r) +
                            // A map without homed_bit cannot tell an unhomed drive, and most
                            // refuse set-points until homed: the refusal read as cryptic (a review).
                            (map_.homed_bit || homed_
                                 ? ""
                                 : "; a drive that is not homed refuses set-points: run `rig table home` "
                                   "first (drive map " + map_.path + " has no homed_bit to tell)"));
      clock_.sleep_for(opt_.poll_s, cancel);
    }
    write_controlword(c4::cw::kCmdEnableOperation, cancel);  // the drive may now drop the acknowledge
    double timeout = opt_.move_timeout_s;
    if (timeout <= 0) {
      const double v = opt_.velocity_dps.value_or(v_drive);
      double a = opt_.accel_dps2.value_or(0);
      if (a <= 0 && map_.has(Obj::kProfileAcceleration))
        a = map_.accel_units_to_dps2(static_cast<double>(read_object(Obj::kProfileAcceleration, cancel)));
      const double tt = trapezoid_time(deg - start_deg, v, a);
      timeout = tt > 0 ? 2 * tt + opt_.settle_s + 10.0 : kDefaultMoveTimeoutS;
    }
    t0 = clock_.now_s();
    double changed_at = t0;
    detail::HeldFor at_target, reached_off;
    double reached_off_at = NAN;  // where the table rests with target reached, off the target
    Cia402Reading last = r;
    for (;;) {
      clock_.sleep_for(opt_.poll_s, cancel);
      const double asked_at = clock_.now_s();
      r = read(cancel, true);
      fail_on_fault(doing, r);
      const double now = clock_.now_s();
      fail_unless_moving(doing, r, "during the move", target_counts);
      check_pace(r, asked_at, now);
      if (r.has(c4::sw::kFollowingError)) throw HardwareError(doing + ": following error (statusword bit 13)" + at(r));
      const bool ok = r.has(c4::sw::kTargetReached) && std::fabs(r.actual_deg - deg) <= opt_.tolerance_deg;
      if (at_target(ok, now) >= opt_.settle_s) return;
      // Target reached (bit 10) at rest far off the target written: the drive took another target
      // (a map that converts it otherwise than the drive: word order, counts, gear, offset), and
      // only the move timeout ended it (17.5 s in a review, where a rig-v1 table's stop short is
      // said after ended_short_s). As there: held ended_short_s at one place, ten bands off.
      const double band = opt_.tolerance_deg, off = std::fabs(r.actual_deg - deg);
      const bool resting_off = r.has(c4::sw::kTargetReached) && off > 10 * band;
      if (!resting_off || !(std::fabs(r.actual_deg - reached_off_at) <= band)) {
        reached_off(false, now);  // not so, or moved on: the hold starts again from here
        reached_off_at = resting_off ? r.actual_deg : NAN;
      }
      if (const double held = reached_off(resting_off, now); held >= opt_.ended_short_s)
        throw HardwareError(doing + ": the drive reads target reached (statusword bit 10) " + deg_str(off) +
                            " off the target written, at rest for " + secs(held) +
                            ": it took another target (check the map's word_order, counts_per_rev, gear_ratio and "
                            "home offset against the drive's manual)" + at(r));
      // Heading away from the target, past the distance it started from by more than a servo
      // overshoots: the drive runs to another target first (it took this set-point into its
      // buffer without "change set immediately" and continues a halted move; a review could not
      // rule such a drive out, and only the timeout ended it). Not sooner on the far side of the
      // target: a ringing servo overshoots a short move by about half its length (damping 0.2-0.3,
      // a review; half the move as the margin failed its good moves).
      const double away = std::fabs(r.actual_deg - deg), from = std::fabs(start_deg - deg);
      if (away > from + std::max(1.0, 10 * opt_.tolerance_deg))
        throw HardwareError(doing + ": the table moves away from the target (" + deg_str(away) + " off, it started " +
                            deg_str(from) + " off): the drive running to another target first (a halted move it "
                            "continues?), or the map's word_order not the drive's, so that the drive took another "
                            "target than the one written (check word_order against the drive's manual; a mapped "
                            "device_type lets the rig check it before any move)" + at(r));
      // No heartbeat object in CiA 402: a drive whose statusword and position
      // stop changing while the target is not reached is taken for frozen.
      if (r.statusword != last.statusword || std::fabs(r.actual_deg - last.actual_deg) > 1e-9 ||
          r.has(c4::sw::kTargetReached))
        changed_at = now;
      last = r;
      if (now - changed_at > opt_.heartbeat_timeout_s)
        throw HardwareError(doing + ": drive frozen: statusword and position actual unchanged for " +
                            secs(now - changed_at) + " while moving" + at(r));
      if (now - t0 > timeout) {
        const std::string state = !r.has(c4::sw::kTargetReached) ? "target not reached"
                                  : "stopped " + deg_str(std::fabs(r.actual_deg - deg)) + " off target (tolerance " +
                                        deg_str(opt_.tolerance_deg) + ")";
        throw HardwareError(doing + ": timed out after " + secs(now - t0) + ", " + state + at(r));
      }
    }
  });
}

uint16_t Cia402Table::reset_fault(const CancelToken& cancel) {
  const std::string doing = "fault reset";
  try {
    Cia402Reading r = read(cancel);
    const double t_react = clock_.now_s();
    while (r.state() == State::kFaultReactionActive && clock_.now_s() - t_react < opt_.ack_timeout_s) {
      clock_.sleep_for(opt_.poll_s, cancel);  // the drive is still braking: Fault follows (transition 14)
      r = read(cancel);
    }
    if (r.state() != State::kFault) return 0;
    const uint16_t code = r.error_code;
    write_controlword(0, cancel);
    write_controlword(c4::cw::kFaultReset, cancel);  // rising edge: transition 15
    write_controlword(0, cancel);
    const double t0 = clock_.now_s();
    while ((r = read(cancel)).state() == State::kFault && clock_.now_s() - t0 < opt_.ack_timeout_s)
      clock_.sleep_for(opt_.poll_s, cancel);
    if (r.state() == State::kFault)
      throw HardwareError(doing + ": drive \"" + map_.name + "\" stays in Fault, error code " + hex4(r.error_code) +
                          " " + c4::error_code_text(r.error_code) + " (its cause is still present)");
    return code;
  } catch (const ModbusError& e) {
    throw HardwareError(doing + ": link failure: " + e.what());
  }
}

void Cia402Table::send_stop(uint16_t word, const char* name) noexcept {
  {
    std::lock_guard lk(stop_mu_);
    stop_needless_ = false;
  }
  detail::deliver_stop(
      name,
      [&] {
        // Before the write: a move polling meanwhile reads the halt back as this client's own,
        // not another master's.
        control_ = word;
        write_object(Obj::kControlword, word, CancelToken{}, true);
        control_written_ = true;
      },
      stop_mu_, last_stop_error_);
}

// Halt keeps the drive in the state it is in (never enables or disables anything) and drops
// new-set-point so no move is taken after it. Its device control bits are the command that
// holds the state the drive reports now (statusword, one urgent read): a quick stop or disable
// another master made since this client's last write is kept (a review: the halt was built from
// the word this client wrote, Enable operation, and took a quick-stopped drive back to Operation
// enabled, 5 degrees further). Not the controlword read back: a gateway may read the write-only
// 0x6040 as 0, and a halt with 0 is Disable voltage (a code review). Where the read fails, the
// last word this client wrote; without one, it sends nothing rather than a guess that could drop
// the power stage mid-move.
namespace {
// The states whose power stage is off (none of them left by this client's own commands): a halt
// there is Disable voltage, so stop_goes_out asks the axis whether it is at rest, and stop()
// builds no halt from them.
bool power_stage_off(State s) {
  return s == State::kNotReadyToSwitchOn || s == State::kSwitchOnDisabled || s == State::kFault;
}

// Ready to switch on and Switched on: the power stage may be on but the drive function is
// disabled, so nothing turns under power there either; a halt built from them is Shutdown or
// Switch on (0x0106, 0x0107), which takes a drive really in Operation enabled out of it mid-move.
bool drive_function_disabled(State s) { return s == State::kReadyToSwitchOn || s == State::kSwitchedOn; }

uint16_t command_holding(State s) {
  switch (s) {
    case State::kOperationEnabled: return c4::cw::kCmdEnableOperation;
    case State::kQuickStopActive: return c4::cw::kCmdQuickStop;
    case State::kSwitchedOn: return c4::cw::kCmdSwitchOn;
    case State::kReadyToSwitchOn: return c4::cw::kShutdown;
    default: return c4::cw::kDisableVoltage;  // Switch on disabled, Not ready, Fault (none of them left by it)
  }
}
}  // namespace

// Whether a stop (`name`) goes out, given the statusword just read: not into a device this client
// has not identified and that is not the drive (identity_problem: a second review found a rig-v1
// table in motion, statusword-like 0x0417, taken for Quick stop active and halted with 0x0102),
// and not where the power stage is off (Not ready to switch on, Switch on disabled, Fault: nothing
// can move, and a halt there is Disable voltage written into whatever the statusword address
// really is, e.g. a map with the statusword and error code swapped). Records why not.
bool Cia402Table::stop_goes_out(uint16_t statusword, const char* name) noexcept {
  std::string why;
  bool needless = false;
  try {
    if (!identified_) {
      try {
        bool is_402 = false;
        why = identity_problem(statusword, CancelToken{}, true, &is_402);
        if (why.empty()) identified_ = true;
        // A CiA 402 drive whose 32-bit words the map reads in the other order: its controlword
        // and statusword are 16-bit, so the stop means what it says; it goes out (a review: the
        // halt was refused and the table ran on to its target).
        if (is_402) why.clear();
      } catch (...) {  // a device type that cannot be read now: the statusword decides
      }
      if (!why.empty()) why = std::string(name) + " not sent (the table may still be moving): " + why + " (" + kWhichDrive + ")";
    }
    const State st = c4::decode_state(statusword);
    // The axis must read at rest too (one more urgent read): a statusword address that is wrong
    // may read 0, Not ready, while the table turns (a review: "no halt needed", exit 0, and the
    // move went on). Moving, or unread: the halt goes out as it always did.
    // A word that is none of the states says nothing of the power stage (0xFFFF decodes to the
    // fallback Not ready to switch on): the stop goes out (a code review).
    if (why.empty() && c4::is_state(statusword) && power_stage_off(st)) {
      if (axis_reads_at_rest()) {
        why = std::string("no ") + name + " needed: drive \"" + map_.name + "\" in " + c4::state_name(st) +
              " (statusword " + hex4(statusword) + ") and at rest: its power stage is off";
        needless = true;
      }
    }
  } catch (...) {
    return true;
  }
  if (why.empty()) return true;
  detail::record_stop(stop_mu_, last_stop_error_, std::move(why), [&] { stop_needless_ = needless; });
  return false;
}

// One urgent read of velocity actual; false where it reads moving or cannot be read.
bool Cia402Table::axis_reads_at_rest() noexcept {
  try {
    return std::fabs(map_.velocity_units_to_dps(static_cast<double>(read_object(Obj::kVelocityActual, CancelToken{}, true)))) <= kRestDps;
  } catch (...) {
    return false;
  }
}

// Each stop or quick stop asked for, sent or not (the power stage off: "no halt needed"), ends
// a move or homing run under way before its next command word (StopLatch): one that is still
// switching the drive on would otherwise enable it and move (a review).
// A statusword that reads the power stage off or faulted (Not ready to switch on, Switch on
// disabled, Fault, Fault reaction active) while the axis reads moving or its velocity cannot be
// read (stop_goes_out lets such a halt out) is an axis coasting, or a statusword address that is
// wrong: the halt built from it was Disable voltage, 0x0100, which on a drive
// really in Operation enabled switches the power stage off mid-move (a review: a map with the
// statusword and error code swapped, "stop sent", exit 0). The quick stop command with halt,
// 0x0102, enables nothing in any state and quick-stops a drive in Operation enabled; it is sent
// instead and said as a fault (the table may still be moving). Ready to switch on and Switched on
// alike where the axis reads moving or its velocity cannot be read (their halts, 0x0106 and 0x0107,
// are Shutdown and Disable operation to a drive really in Operation enabled); at rest, their halt
// holds the state as before.
void Cia402Table::stop() noexcept {
  const detail::StopLatch::Asking counted(stops_, false);
  uint16_t bits = 0;
  bool known = false;
  std::string off_yet_moving, unread;
  try {
    const auto sw = static_cast<uint16_t>(read_object(Obj::kStatusword, CancelToken{}, true));
    if (!stop_goes_out(sw, "halt")) return;
    const State st = c4::decode_state(sw);
    bits = command_holding(st);
    known = true;
    // This client's standing quick stop makes the word 0x0102 anyway (below): no read, no blame.
    const bool disabled_yet_moving = drive_function_disabled(st) && !stops_.quick_stop_stands() && !axis_reads_at_rest();
    if (power_stage_off(st) || st == State::kFaultReactionActive || disabled_yet_moving) {
      bits = c4::cw::kCmdQuickStop;
      // The axis was asked in the power-off states (stop_goes_out) and the drive-function-disabled
      // ones (just above): Fault reaction active is not claimed to read moving.
      off_yet_moving = "halt delivered to the drive as the quick stop command (controlword 0x0102): " +
                       map_.describe(Obj::kStatusword) + " reads " + hex4(sw) + ", " +
                       (c4::is_state(sw) ? c4::state_name(st) : std::string("none of the CiA 402 states")) +
                       (!c4::is_state(sw) ? std::string(", while the axis reads moving or its velocity could not be read")
                        : st == State::kFaultReactionActive
                            ? " (a drive reacting to a fault)"
                            : std::string(power_stage_off(st) ? " (power stage off or faulted)" : " (drive function disabled)") +
                                  ", while the axis reads moving or its velocity could not be read") +
                       ": an axis coasting, or a statusword address that is wrong (check the drive map); the "
                       "table may still be moving";
    }
  } catch (const detail::NotThisDriveError& e) {  // another protocol answers: no drive, no halt, and no
    // quick stop either (quick_stop refuses that peer too): the "quick-stop needs no word" advice was wrong there
    stop_not_sent({"halt not sent: ", e.what()});
    return;
  } catch (const std::exception& e) {
    try {
      unread = e.what();
    } catch (...) {
    }
  } catch (...) {
  }
  // This client's quick stop stands whatever the statusword showed (the drive may not have taken
  // it yet): the halt keeps its command.
  if (stops_.quick_stop_stands()) bits = c4::cw::kCmdQuickStop, known = true;
  // Only a word this client wrote: one read back may be a gateway's 0 (Disable voltage).
  if (!known && control_written_) bits = static_cast<uint16_t>(control_.load() & 0x000F), known = true;
  if (!known) {
    // Said with what failed and what still works: the quick stop command needs no word to keep
    // (a technician at a silent link read "read the status first").
    std::string why = "halt not sent: the controlword is unknown (the statusword could not be read";
    try {
      why += (unread.empty() ? std::string() : ": " + unread) +
             ", and this client has written none); `rig table quick-stop` sends the quick stop command, which needs none";
    } catch (...) {
    }
    detail::record_stop(stop_mu_, last_stop_error_, std::move(why), [&] { stop_needless_ = false; });
    return;
  }
  send_stop(static_cast<uint16_t>(bits | c4::cw::kHalt), "halt");
  if (!off_yet_moving.empty() && last_stop_error().empty())
    detail::record_stop(stop_mu_, last_stop_error_, std::move(off_yet_moving), [&] { stop_needless_ = false; });
}

void Cia402Table::stop_not_sent(std::initializer_list<std::string_view> said) noexcept {
  std::string why;
  try {
    for (const std::string_view part : said) why += part;
  } catch (...) {
  }
  detail::record_stop(stop_mu_, last_stop_error_, std::move(why), [&] { stop_needless_ = false; });
}

// Sent at once by a client that has identified its drive; else after one urgent statusword read
// (a read met by silence, a Modbus reply that breaks the protocol or a broken link still sends:
// the link decides then, as before; one answered in another protocol does not: that peer is not
// the drive).
void Cia402Table::quick_stop() noexcept {
  const detail::StopLatch::Asking counted(stops_, true);
  if (!identified_) {
    try {
      if (!stop_goes_out(static_cast<uint16_t>(read_object(Obj::kStatusword, CancelToken{}, true)), "quick stop")) return;
    } catch (const detail::NotThisDriveError& e) {  // read_object: another protocol answered, no drive
      stop_not_sent({"quick stop not sent (the table may still be moving): ", e.what()});
      return;
    } catch (const ModbusError& e) {  // identified meanwhile by another thread's reading: said here
      if (e.foreign_reply) {
        stop_not_sent({"quick stop not sent (the table may still be moving): ", e.what(), " (", kForeignPeer, ")"});
        return;
      }
    } catch (...) {
    }
  }
  send_stop(c4::cw::kCmdQuickStop, "quick stop");
  stops_.quick_stop_sent(last_stop_error().empty());
}

}  // namespace rig::modbus
