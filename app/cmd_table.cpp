// `rig table`: manual control of a real or emulated rotary table over Modbus,
// for a technician at the rig (docs/table-registers.md).
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "app/commands.hpp"
#include "app/endpoint_option.hpp"
#include "app/hardware_file.hpp"
#include "app/number_option.hpp"
#include "app/output_file.hpp"
#include "app/station_stop.hpp"
#include "app/table_lock.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/executive/signals.hpp"
#include "rig/modbus/cia402_client.hpp"
#include "rig/modbus/motion_text.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::cli {

namespace {

struct TableArgs {
  std::string modbus, rtu, hardware, drive, drive_map;
  std::optional<int> unit;
  std::optional<double> timeout_s;
  double deg = 0;
  bool json = false;
};

// The [table] settings: from --hardware FILE, overridden by the flags. The
// section is edited in place inside `root` (the parsed file) so the file's
// own keys keep their line numbers in error messages. The file is checked with
// the flags in: a key refused for the drive protocol then names the protocol the
// command uses (--drive over the file's; an outside review found the file's named).
toml::table& table_config(const TableArgs& a, toml::table& root) {
  if (a.drive == "rig-v1" && !a.drive_map.empty()) throw ConfigError("rig table: --drive-map is for --drive cia402");
  std::string alone;  // why the file as it stands is refused (`rig run --hardware` refuses it so)
  if (!a.hardware.empty()) {
    root = cfg::parse_file(a.hardware);
    try {
      validate_hardware(root, {"table"});
    } catch (const ConfigError& e) {
      if (!root.get_as<toml::table>("table")) throw;  // no [table] to apply the flags to
      alone = e.what();
    }
  } else {
    root.insert_or_assign("table", toml::table{});
  }
  toml::table& t = *root.get_as<toml::table>("table");
  // The options' own combinations, named as options: they read "command-line option: drive_map
  // is for drive = "cia402"" (a technician's review). A file's keys are named at their lines below.
  const std::string file_drive = t["drive"].value_or(std::string());
  if (!a.drive_map.empty() && a.drive.empty() && file_drive != "cia402")
    throw ConfigError("rig table: --drive-map is for --drive cia402 (the drive is rig-v1 unless --drive or the hardware "
                      "file's [table] drive says cia402)");
  if (a.drive == "cia402" && a.drive_map.empty() && !t.contains("drive_map"))
    throw ConfigError("rig table: --drive cia402 needs --drive-map FILE (a CiA 402 drive map: drives/*.toml)");
  if (!a.drive.empty()) t.insert_or_assign("drive", a.drive);
  if (!a.drive_map.empty()) t.insert_or_assign("drive_map", a.drive_map);
  // The file's map, checked above, is not this protocol's: left out, and said (it was silent).
  if (a.drive == "rig-v1" && t.contains("drive_map")) {
    cfg::warn_once(cfg::where(*t.get("drive_map")) + ": drive_map is for a CiA 402 drive: not used with --drive rig-v1");
    t.erase("drive_map");
  }
  if (!a.modbus.empty()) {
    t.erase("rtu");
    t.insert_or_assign("modbus", a.modbus);
  }
  if (!a.rtu.empty()) {
    t.erase("modbus");
    t.insert_or_assign("rtu", a.rtu);
  }
  if (a.unit) t.insert_or_assign("unit", *a.unit);
  if (a.timeout_s) t.insert_or_assign("response_timeout_s", *a.timeout_s);
  if (!a.hardware.empty()) {
    validate_hardware(root, {"table"});  // with the flags in: a refusal names what the command uses
    // Right only with the flags: used, and said, since the file alone is refused elsewhere.
    if (!alone.empty())
      cfg::warn_once(alone + " (taken here with the command line's options over the file; `rig run --hardware " +
                     a.hardware + "` refuses it)");
  }
  if (!t.contains("modbus") && !t.contains("rtu"))
    throw ConfigError("rig table: say where the table is: --modbus HOST:PORT, --rtu DEV[,BAUD] or --hardware FILE");
  return t;
}

// Ctrl-C, SIGTERM or a closed terminal (SIGHUP) during a home or a move
// halts the table and exits 3: the same watcher as `rig run`, so no signal
// that ends the process can leave the table turning.
class SignalCancel {
 public:
  CancelToken token() const { return source_.token(); }

 private:
  CancelSource source_;
  SignalWatcher watcher_{source_};
};

std::string flags(const TableStatus& s) {
  std::string f;
  auto add = [&](bool on, const char* name) {
    if (on) f += (f.empty() ? "" : " ") + std::string(name);
  };
  add(s.ready, "ready");
  add(s.servo_on, "servo-on");
  add(s.homed, "homed");
  add(!s.homed_known, "homed-unknown");
  // Moves are refused until it is homed: "ready" alone read as ready to move (a review).
  add(s.homed_known && !s.homed && !s.homing, "NOT-HOMED");
  add(s.homing, "homing");
  add(s.moving, "moving");
  add(s.in_position, "in-position");
  add(s.alarm, "ALARM");
  add(s.estop, "E-STOP");
  add(!s.interlock_ok, "INTERLOCK-OPEN");
  add(s.limit_pos, "LIMIT-POS");  // on the positive over-travel switch (a review: the alarm alone
  add(s.limit_neg, "LIMIT-NEG");  // did not say which way to move off it)
  return f.empty() ? "-" : f;
}

// Whether the table, at rest, stands where the drive's target says (within the move tolerance):
// after an aborted move the target still holds the aborted goal while the drive reads in position
// at its stop point, which read as "arrived" to an operator (a review). The target is the drive's
// register (rig-v1 TARGET_POS, CiA 402 0x607A): a drive may keep the last move's through a home,
// so `home` prints no such note (a code review).
bool at_rest_off_target(const TableStatus& s, double tolerance_deg) {
  return !s.moving && !s.homing && std::fabs(s.actual_deg - s.target_deg) > tolerance_deg;
}

void print_status(const std::string& where, const TableStatus& s, bool json, double tolerance_deg) {
  const bool off = at_rest_off_target(s, tolerance_deg);
  if (json) {
    nlohmann::json j = {{"table", where},         {"actual_deg", s.actual_deg}, {"target_deg", s.target_deg},
                        {"ready", s.ready},       {"servo_on", s.servo_on},     {"homed", s.homed},
                        {"homing", s.homing},     {"moving", s.moving},         {"in_position", s.in_position},
                        {"alarm", s.alarm},       {"estop", s.estop},           {"interlock_ok", s.interlock_ok},
                        {"alarm_code", s.alarm_code}, {"alarm_text", s.alarm_text}};
    if (!s.homed_known) j["homed_known"] = false;  // "homed": false then means "cannot tell"
    if (s.has_heartbeat) j["heartbeat"] = s.heartbeat;
    if (!s.drive_state.empty()) j["drive_state"] = s.drive_state;
    if (s.has_limit_switches) {
      j["limit_pos"] = s.limit_pos;
      j["limit_neg"] = s.limit_neg;
    }
    if (!s.moving && !s.homing) j["at_target"] = !off;  // within [table] tolerance_deg, at rest
    std::cout << j.dump(2) << "\n";
    return;
  }
  char alarm[96];
  if (s.alarm_code)
    std::snprintf(alarm, sizeof alarm, "0x%04X %s", s.alarm_code, s.alarm_text.c_str());
  else
    std::snprintf(alarm, sizeof alarm, "none");
  char reached[96] = "";
  if (off)
    std::snprintf(reached, sizeof reached, " (the table is at rest %.4f° from it)",
                  modbus::detail::shown_deg(std::fabs(s.actual_deg - s.target_deg)));
  std::printf("table      %s\nactual     %.4f°\ntarget     %.4f°%s\nstate      %s\nalarm      %s\n", where.c_str(),
              modbus::detail::shown_deg(s.actual_deg), modbus::detail::shown_deg(s.target_deg), reached, flags(s).c_str(),
              alarm);
  if (!s.drive_state.empty()) std::printf("drive      %s (CiA 402)\n", s.drive_state.c_str());
  if (s.has_heartbeat) std::printf("heartbeat  %u\n", s.heartbeat);
}

// What a command's body gets besides the table.
struct TableUse {
  double tolerance_deg;  // the move tolerance
  // modbus::table_identity: the station lock's and the stop note's name. A command holding the lock
  // has it; a stop computes it once sent (a host name's lookup never delays the stop).
  std::optional<std::string> identity;
  const toml::table* cfg;
  std::string id() const { return identity ? *identity : modbus::table_identity(*cfg); }
};

// Runs `body` with the table the arguments name and its TableUse (the move tolerance its settings
// give, its identity).
// `unreachable`: what a failed connection means for the command (a stop: not delivered).
// `command` non-empty (a home, a move, a reset): the station's lock on the table is taken first
// (app/table_lock.hpp), after the settings are checked and before the drive is opened; a status
// or a stop takes none.
template <class Body>
void with_table(const TableArgs& a, Body body, const std::string& unreachable = "", const std::string& command = "") {
  toml::table root;
  const toml::table& t = table_config(a, root);
  // A home, a move or a reset prints where the table ended; started with stdout closed it would
  // turn the table and then exit 2, which a script reads as nothing done (a technician's re-test).
  // Known before anything is sent: refused then. A stop still goes out (it is never refused).
  if (!command.empty() && stdout_closed())
    throw ConfigError("rig table " + command + ": standard output is closed (the command was started with it closed, "
                      ">&-): it prints where the table ended; nothing sent");
  // /dev/full is the one full file known before the first write (`> /dev/full` homed the table,
  // then exit 2: a review); any other full disk is found after the motion, as before.
  if (struct stat st{}; !command.empty() && ::fstat(STDOUT_FILENO, &st) == 0 && S_ISCHR(st.st_mode) &&
                        st.st_rdev == makedev(1, 7))
    throw ConfigError("rig table " + command + ": standard output is /dev/full: it prints where the table ended; "
                      "nothing sent");
  std::optional<std::string> identity;
  std::optional<TableLock> lock;
  if (!command.empty()) {
    identity = modbus::table_identity(t);
    lock.emplace(*identity, "rig table " + command);
    if (!lock->held())  // said, not silent (a review: a missing lock folder turned it off unseen)
      std::cerr << "rig: warning: " << lock->unlocked_warning() << "\n";
  }
  RealClock clock;
  std::unique_ptr<RotaryTable> table;
  try {
    table = modbus::connect_table(t, clock);
  } catch (const HardwareError& e) {
    if (unreachable.empty()) throw;
    throw HardwareError(unreachable + e.what());
  }
  body(*table, TableUse{modbus::table_options_from_toml(t).tolerance_deg, identity, &t});
}

// The two backends' technician-only calls.
std::string last_stop_error(RotaryTable& t) {
  if (auto* c = dynamic_cast<modbus::TableClient*>(&t)) return c->last_stop_error();
  if (auto* c = dynamic_cast<modbus::Cia402Table*>(&t)) return c->last_stop_error();
  return "";
}
void reset(RotaryTable& t, const CancelToken& cancel) {
  if (auto* c = dynamic_cast<modbus::TableClient*>(&t)) c->reset_alarm(cancel);
  if (auto* c = dynamic_cast<modbus::Cia402Table*>(&t)) {
    if (const uint16_t code = c->reset_fault(cancel))
      std::printf("fault reset: cleared error code 0x%04X %s\n", code, modbus::cia402::error_code_text(code).c_str());
  }
}

// While a home or a move waits, the angle the drive reads, on one line of the terminal, at most
// five times a second (a technician saw nothing for the seconds a half turn takes: a review). The
// line is cleared before anything else is printed. Nothing when stderr is not a terminal: a
// script's output stays as it was.
class AngleLine {
 public:
  AngleLine(RotaryTable& t, std::string doing) : t_(t), doing_(std::move(doing)) {
    if (::isatty(STDERR_FILENO)) t_.on_angle([this](double deg) { show(deg); });
  }
  ~AngleLine() {
    t_.on_angle(nullptr);
    clear();
  }
  AngleLine(const AngleLine&) = delete;
  AngleLine& operator=(const AngleLine&) = delete;

 private:
  void clear() {
    if (!shown_) return;
    std::fputs("\r\x1b[K", stderr);
    std::fflush(stderr);
    shown_ = false;
  }
  void show(double deg) {
    const auto now = std::chrono::steady_clock::now();
    if (shown_ && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    std::fprintf(stderr, "\r\x1b[K%s: table at %s", doing_.c_str(), modbus::detail::deg_str(deg).c_str());
    std::fflush(stderr);
    shown_ = true;
  }
  RotaryTable& t_;
  std::string doing_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_;
};

// After Ctrl-C in a move or a homing (the client has sent its halt): where the table came to rest,
// and whether it is still homed, on stderr before the abort's own line. "rig: aborted: SIGINT
// received" alone left a technician guessing (a review: the homed flag was gone, which nothing
// said). Waits up to 10 s for the axis to stop; says so when it cannot read it.
void say_where_it_stopped(RotaryTable& t, bool homing, const std::string& halt_error, const std::string& halted_by = "") {
  try {
    TableStatus s = t.status();
    for (int i = 0; i < 100 && s.moving; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      s = t.status();
    }
    std::cerr << "rig: the table " << (s.moving ? "was still moving" : "stopped") << " at "
              << modbus::detail::deg_str(s.actual_deg)
              << (!halted_by.empty()     ? " (halted by " + halted_by + ")"
                  : halt_error.empty() ? " (halt delivered to the drive)"
                                       : " (" + halt_error + ")")
              << (!s.homed_known ? std::string("; whether it is still homed the drive cannot say (its map has no "
                                               "homed_bit): ") +
                                       (homing ? "the homing was interrupted: `rig table home` before the next move"
                                               : "`rig table home` before the next move if in doubt")
                  : s.homed    ? "; it is still homed"
                               : "; it is not homed now: `rig table home` before the next move")
              << "\n";
  } catch (const std::exception& e) {
    // The halt's fate too: on a dead link it was not delivered, and "after the halt" alone read
    // as if it had been (a review).
    std::cerr << "rig: the table's position could not be read after the " << (halted_by.empty() ? "signal" : "stop")
              << " (" << e.what() << "); "
              << (!halted_by.empty()     ? "halted by " + halted_by
                  : halt_error.empty() ? "halt delivered to the drive"
                                       : halt_error)
              << ": check it with `rig table status` before anything else\n";
  }
}

// Runs a home or a move (`motion`, `doing` naming it). Ctrl-C: the client has sent its halt;
// where the table came to rest is said and the abort goes on (exit 3). A halt by `rig table stop`
// from this station's other terminal: said so, where it came to rest, and exit 3 too
// (app/station_stop.hpp).
template <class Motion>
void run_motion(RotaryTable& t, const TableUse& use, const std::string& doing, Motion motion) {
  std::string by;  // who halted it, where a stop from this station did
  try {
    AngleLine line(t, doing);
    motion_stoppable_from_this_station(use.id(), doing, motion, [&](const std::string& who) { by = who; });
  } catch (const AbortedError&) {  // the angle line cleared first
    say_where_it_stopped(t, doing == "homing", by.empty() ? last_stop_error(t) : "", by.empty() ? "" : by + " on this station");
    throw;
  }
}

}  // namespace

void add_table(CLI::App& app, int& rc) {
  auto a = std::make_shared<TableArgs>();
  auto* sub = app.add_subcommand("table", "Manual control of the rotary table over Modbus (status, home, move, stop)");
  sub->require_subcommand(1);
  auto* where = sub->add_option("--modbus", a->modbus, "Modbus TCP drive, HOST:PORT or [IPv6]:PORT")
                     ->check(modbus_endpoint_option(EndpointOption::kDrive));
  sub->add_option("--rtu", a->rtu, "Modbus RTU drive, DEVICE[,BAUD[,PARITY,DATABITS,STOPBITS]] (default 19200,E,8,1)")
      ->check(modbus_endpoint_option(EndpointOption::kSerial))
      ->excludes(where);
  sub->add_option("--hardware", a->hardware, "Take the [table] section of this hardware file (flags override)");
  sub->add_option("--unit", a->unit, "Modbus unit id (default 1)")->check(CLI::Range(1, 247));
  // NaN passed CLI11's Range (every comparison false) and was named by its internal key,
  // 'response_timeout_s' (a technician's review): one check, the value named as typed.
  sub->add_option("--timeout", a->timeout_s, "Response timeout per request, seconds (default 0.3)")
      ->check(number_in(0.01, 10.0, false, "a number of seconds"));
  sub->add_option("--drive", a->drive, "Drive protocol: rig-v1 (default) or cia402")
      ->check(CLI::IsMember({"rig-v1", "cia402"}));
  sub->add_option("--drive-map", a->drive_map, "CiA 402 drive map file (drives/*.toml), with --drive cia402");

  auto* st = sub->add_subcommand("status", "Read and print the drive's status");
  st->add_flag("--json", a->json, "Print JSON");
  st->callback([a, &rc] {
    with_table(*a, [&](RotaryTable& t, const TableUse& use) {
      print_status(t.describe(), t.status(), a->json, use.tolerance_deg);
    });
    rc = kExitPass;
  });

  sub->add_subcommand("home", "Run the homing sequence and wait until homed")->callback([a, &rc] {
    with_table(*a, [&](RotaryTable& t, const TableUse& use) {
      SignalCancel sig;
      run_motion(t, use, "homing", [&] { t.home(sig.token()); });
      print_status(t.describe(), t.status(), false, std::numeric_limits<double>::infinity());  // no target note
    }, "", "home");
    rc = kExitPass;
  });

  auto* mv = sub->add_subcommand("move", "Move to an angle and wait until in position and confirmed");
  // A finite angle, checked on the text before the drive is asked: `move nan` was exit 4 with the
  // drive unreachable and 2 with it reachable, and `move 1e400` was named "inf°" (a review). The
  // travel limits are the drive's, checked when it answers.
  mv->add_option("DEG", a->deg, "Target angle, degrees, in [-200000, 200000] (the drive's travel limits checked when it answers)")
      ->required()
      ->check(number_in(-200000.0, 200000.0, false, "a number of degrees"));  // the client's bound, before the drive is asked
  mv->callback([a, &rc] {
    with_table(*a, [&](RotaryTable& t, const TableUse& use) {
      SignalCancel sig;
      run_motion(t, use, "moving to " + modbus::detail::deg_str(a->deg), [&] { t.move_to(a->deg, sig.token()); });
      print_status(t.describe(), t.status(), false, use.tolerance_deg);
    }, "", "move " + modbus::detail::deg_str(a->deg));
    rc = kExitPass;
  });

  auto stop_cmd = [a, &rc](bool quick) {
    // The stop is the result, its line a confirmation: a reader gone (`rig table stop | head -0`)
    // ended it with SIGPIPE's 141 after the stop went out (a code review). Its exit code is the stop's.
    ::signal(SIGPIPE, SIG_IGN);
    with_table(*a, [&](RotaryTable& t, const TableUse& use) {
      // rig-v1: learn CONTROL first (a read with the link's retries), so the stop keeps SERVO_ON
      // as the drive holds it: the stop's own urgent read is one attempt and a reconnect, and a
      // fresh client that learned nothing writes HALT with SERVO_ON clear, which brakes the servo
      // off (a code review). On a lossy link the retries are what learns it; on a silent one they
      // cost their timeouts (2.25 s at the 0.3 s default, a review; README says so). A CiA 402
      // stop reads its statusword itself and builds nothing from a status read, so it goes
      // straight out (two timeouts fewer on a silent link).
      if (dynamic_cast<modbus::Cia402Table*>(&t) == nullptr) {
        try {
          t.status();
        } catch (const HardwareError&) {
        }
      }
      if (quick) {
        t.quick_stop();
      } else {
        t.stop();
      }
      // A CiA 402 drive whose power stage is off needs no stop, and gets none (exit 0, said so).
      if (auto* c = dynamic_cast<modbus::Cia402Table*>(&t); c && c->last_stop_needless()) {
        std::cout << c->last_stop_error() << "\n";
        return;
      }
      // A stop whose servo bit was a guess says so, delivered or not (a review: a slow link's
      // stop switched the servo off and said only "not delivered").
      const auto* v1 = dynamic_cast<modbus::TableClient*>(&t);
      const std::string note = v1 ? v1->last_stop_note() : std::string();
      if (!last_stop_error(t).empty())
        throw HardwareError(last_stop_error(t) + (note.empty() ? "" : "; if it reached the drive: " + note));
      // Delivered: a move this halts in another terminal of this station names this command.
      const std::string unnoted = TableLock::note_stop(use.id(), quick ? "rig table quick-stop" : "rig table stop");
      if (!unnoted.empty())
        std::cerr << "rig: warning: the stop's note beside the table lock was not left (" << unnoted
                  << "): a move it halted in another terminal says \"halted by another master\" (exit 4)\n";
      std::cout << (quick ? "quick stop" : "stop") << " sent to " << t.describe() << (note.empty() ? "" : "; " + note)
                << "\n";
    }, std::string(quick ? "quick stop" : "stop") + " not delivered (the table may still be moving): ");
    rc = kExitPass;
  };
  sub->add_subcommand("stop", "Controlled stop (halt on the profile ramp)")->callback([stop_cmd] { stop_cmd(false); });
  sub->add_subcommand("quick-stop", "Quick stop (the drive's quick-stop ramp), then hold")->callback([stop_cmd] {
    stop_cmd(true);
  });
  sub->add_subcommand("reset", "Reset the drive's alarm after inspection (refused while e-stop/interlock open)")
      ->callback([a, &rc] {
        with_table(
            *a,
            [&](RotaryTable& t, const TableUse& use) {
              reset(t, {});
              print_status(t.describe(), t.status(), false, use.tolerance_deg);
            },
            "", "reset");
        rc = kExitPass;
      });
  // The connection options may come before or after the action:
  // `rig table home --modbus HOST:PORT` as well as `rig table --modbus HOST:PORT home`.
  for (CLI::App* action : sub->get_subcommands({})) action->fallthrough();
}

}  // namespace rig::cli
