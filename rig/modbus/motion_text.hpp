// Small pieces both table clients (rig-v1 map and CiA 402) use in their waits and messages:
// angle, code and duration formatting, a trapezoidal move's duration for time bounds, and the
// one way a table call fails (stop first, then say what was being done and the stop's fate).
#pragma once
#include <cmath>
#include <cstdio>
#include <exception>
#include <mutex>
#include <string>

#include "rig/core/errors.hpp"
#include "rig/core/table.hpp"
#include "rig/modbus/transport.hpp"

namespace rig::modbus::detail {

// An angle as people read it: four decimals, and no "-0.0000°" for a value that rounds to zero
// (a home read back as -0.00001° printed so, a review).
inline double shown_deg(double d) { return std::fabs(d) < 0.00005 ? 0.0 : d; }
inline std::string deg_str(double d) {
  char b[48];
  std::snprintf(b, sizeof b, "%.4f°", shown_deg(d));
  return b;
}

// A value refused at a limit it reads the same as at four decimals, with the digits that tell
// them apart ("move to 370.00004°: outside [..., 370.0000°]" read as a contradiction; a review).
inline std::string deg_str_past(double d, double limit) {
  if (deg_str(d) != deg_str(limit)) return deg_str(d);
  char b[48];
  std::snprintf(b, sizeof b, "%.10g°", shown_deg(d));
  return b;
}

inline std::string hex4(unsigned v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%04X", v);
  return b;
}

inline std::string secs(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f s", s);
  return b;
}

// Writes one [table] setting (`write` sends it); a value the drive refuses (exception 0x03,
// illegal data value: above its maximum, say) is named by the key it came from and where that
// was written (`where`, "file:line:col", or empty), not only by its register: the drive's
// limits are the drive's to know, so this is found at the first command.
template <class Write>
void write_setting(const std::string& where, const char* key, double value, Write write) {
  try {
    write();
  } catch (const ModbusError& e) {
    if (e.exception_code != 3) throw;
    char shown[32];
    std::snprintf(shown, sizeof shown, "%g", value);
    throw HardwareError((where.empty() ? std::string() : where + ": ") + "[table] " + key + " = " + shown + ": the drive refused the value: " + e.what());
  }
}

// Duration of a trapezoidal move (rig/core/table.hpp: the procedure's plan uses it too).
using rig::trapezoid_time;

// Records under `mu` in `last_error` what became of a stop: empty, it reached the drive; else why
// not (read by the fault messages, guarded_call, and `rig table stop`). `also` runs under the same
// lock (a client's other stop state). Never throws: it is on the safe-state path.
template <class Also>
void record_stop(std::mutex& mu, std::string& last_error, std::string&& why, Also also) noexcept {
  try {
    std::lock_guard lk(mu);
    last_error = std::move(why);
    also();
  } catch (...) {
  }
}
inline void record_stop(std::mutex& mu, std::string& last_error, std::string&& why) noexcept {
  record_stop(mu, last_error, std::move(why), [] {});
}

// One attempt to deliver a stop (`write` sends it) on the safe-state path: never throws, and
// records whether it reached the drive.
template <class Write>
void deliver_stop(const char* name, Write write, std::mutex& mu, std::string& last_error) noexcept {
  std::string err;
  try {
    write();
  } catch (const std::exception& e) {
    // A timeout is most often a request sent and not answered: a drive that hangs takes it when it
    // runs again (a bring-up review: "not delivered", and the drive read Quick stop active once
    // resumed). Not always (a send that timed out sent nothing), and an earlier attempt may have
    // gone out before a reconnect failed: so "not confirmed", never "sent".
    const auto* m = dynamic_cast<const ModbusError*>(&e);
    try {
      err = std::string(name) +
            (m && m->timeout ? " not confirmed (unanswered in time: the drive may still take it when it answers again; "
                               "the table may still be moving): "
                             : " not delivered (the table may still be moving): ") +
            e.what();
    } catch (...) {
    }
  } catch (...) {
  }
  record_stop(mu, last_error, std::move(err));
}

// Another master took the axis mid-call (its set-point, its halt, its mode): the call ends at once
// and sends no halt of its own, which would stop the other master's motion (a review: the halt
// ended the other master's move, which then timed out "off target").
struct TakenOverError : HardwareError {
  using HardwareError::HardwareError;
};

// How long a condition read at each poll has held without a break, on the client's clock: the
// settle of a move (in position for settle_s), a homing run ended short of its home (below).
class HeldFor {
 public:
  // Seconds `holds` has been true up to `now` (0 at the poll it became true); -1 while it is not.
  double operator()(bool holds, double now) {
    if (!holds) return since_ = -1;
    if (since_ < 0) since_ = now;
    return now - since_;
  }

 private:
  double since_ = -1;
};

// The device answering is not the drive the configuration names (its statusword is no state of
// the standard, its device type another profile): refused before anything is written, and no halt
// follows, since a halt written to another device's register map is a guess (a review: a CiA 402
// quick stop, controlword 0x0002, is START with SERVO_ON clear on a rig-v1 table).
struct NotThisDriveError : HardwareError {
  using HardwareError::HardwareError;
};

// Runs `body`; on an abort or a fault (but TakenOverError) it stops the axis first (`stop`, which
// never throws and returns the name of the stop it sent: "halt", or "quick stop" where one was
// asked) and rethrows. A fault's message says what was being done, `where()` (read at the fault:
// e.g. the last angle seen) and whether the stop reached the drive (`stop_error()` empty:
// delivered) — a technician must know if the table may still be turning. An exception reply means the drive refused a request; no
// code means the link failed.
template <class Body, class Where, class Stop, class StopError>
void guarded_call(const std::string& doing, Body body, Where where, Stop stop, StopError stop_error) {
  const char* sent = "halt";  // what `stop` sent (it returns its name: a halt, or a quick stop asked)
  auto stop_fate = [&] {
    const std::string err = stop_error();
    return err.empty() ? "; " + std::string(sent) + " delivered to the drive" : "; " + err;
  };
  try {
    body();
  } catch (const AbortedError&) {
    sent = stop();
    throw;
  } catch (const NotThisDriveError&) {
    throw;
  } catch (const TakenOverError& e) {
    // Its type kept: `rig table` tells a stop from this station (app/table_lock.hpp) by it.
    throw TakenOverError(e.what() + std::string("; no halt sent by this client: another master commands the table"));
  } catch (const ModbusError& e) {
    sent = stop();
    throw HardwareError(doing + (e.exception_code ? ": request refused" : ": link failure") + where() + ": " +
                        e.what() + stop_fate());
  } catch (const HardwareError& e) {
    sent = stop();
    throw HardwareError(e.what() + stop_fate());
  }
}

// The reading a move takes before it writes anything (to refuse an unhomed table with nothing
// sent): a failure of that read (the link, an abort) takes the usual path of a move's failure
// through `guard` (a guarded call: the stop tried, its fate said) and is rethrown.
template <class Read, class Guard>
auto read_before_motion(Read read, Guard guard) -> decltype(read()) {
  try {
    return read();
  } catch (...) {
    const std::exception_ptr failed = std::current_exception();
    guard([&] { std::rethrow_exception(failed); });
    std::rethrow_exception(failed);  // (guard rethrows; never reached)
  }
}

}  // namespace rig::modbus::detail
