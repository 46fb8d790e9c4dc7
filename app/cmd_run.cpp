// `rig run`: the acceptance procedure, end to end, with a run folder holding
// the captures, checkpoint, passport.json, junit.xml, analysis.json,
// report.html and run.log. Exit codes per docs/contracts.md.
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstdlib>
#include <cctype>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <signal.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <string_view>
#include <set>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "firmware_link/connect.hpp"
#include "rig/core/file_text.hpp"
#include "rig/core/json_unique.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "plant/emulated/plant_config.hpp"
#include "plant/emulated/world.hpp"
#include "plant/firmware/firmware_config.hpp"
#include "plant/table/table_emulator.hpp"
#include "procedures/acceptance/analysis_doc.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "app/abort_cleanup.hpp"
#include "app/backends.hpp"
#include "app/injections.hpp"
#include "app/run_folder.hpp"
#include "app/run_seal.hpp"
#include "app/passport_held.hpp"
#include "app/folder_lock.hpp"
#include "app/table_lock.hpp"
#include "app/serial_option.hpp"
#include "app/fast_forward.hpp"
#include "app/commands.hpp"
#include "app/error_words.hpp"
#include "app/existing_path.hpp"
#include "app/whole_number.hpp"
#include "app/history_source.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/file_stamp.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/executive/passport.hpp"
#include "rig/executive/signals.hpp"
#include "rig/executive/terminal.hpp"
#include "rig/modbus/table_client.hpp"
#include "rig/report/db.hpp"
#include "rig/report/history.hpp"
#include "rig/report/timefmt.hpp"
#include "rig/report/passport_read.hpp"
#include "rig/report/report.hpp"
#include "rig/core/path_kind.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

namespace {

struct RunArgs {
  std::string plant = "emulated";
  std::string hardware;
  std::string profile = "paper";
  std::string serial;
  std::string out;
  std::string resume;
  std::string resume_serial;  // --serial given with --resume: the DUT the operator says is mounted
  std::string db;
  bool db_from_run_json = false;  // a resume's --db taken from its run.json (messages say so)
  // run.json's history_db where the resume cannot take it (its password masked): compared with the
  // database the resume resolves once the hardware file is read (do_run, before the history check).
  std::string run_history_db;
  std::string seal_key;  // --seal-key / RIG_SEAL_KEY: the station's key (docs/seal.md)
  bool seal_key_given = false;
  std::vector<std::string> inject;
  bool yes = false;
  bool dry_run = false;
  bool quiet = false;
  bool no_history = false;
  // A resume told --no-history or another --db than its run records into (run.json): the run's own
  // database keeps the earlier ending's row. Said when the run starts; under --no-history a
  // verdict's ending lists `history` in .ending-pending, owed to that database (an automation
  // review: the row stayed ABORTED for a DUT whose resume FAILed, nothing saying a row was owed).
  std::string history_left_behind;  // the warning, "" when the resume records where its run does
  bool history_owed = false;        // --no-history over a run that records: the row is owed
  std::string record_command;       // how to record the folder into the run's database (a resume's, from run.json)
  // run.json's station: where the run was measured. Its resume's passport and history row keep it,
  // wherever the resume runs (one that opens no device may run on another machine, whose host name
  // the station fell back to: two rows for one run). "" for an older run.json: the station as now.
  std::string station;
  // SHA-256 of the profile's text as the run copies it to profile.toml, taken when the run starts
  // (the file named by --profile may change while the run goes on): passport.json's profile_sha256.
  std::string profile_sha256;
};

// run.json of a run folder, checked before it is trusted: each field has its type, the
// plant is one rig knows, and a hardware run names its hardware file.
void read_invocation(const std::string& path, const nlohmann::json& inv, RunArgs& a) {
  if (!inv.is_object()) throw ConfigError(path + ": expected a JSON object, found " + inv.type_name());
  auto str = [&](const char* key, const std::string& dflt) {
    if (!inv.contains(key)) return dflt;
    if (!inv[key].is_string())
      throw ConfigError(path + ": field '" + key + "': expected a string, found " + inv[key].type_name());
    return inv[key].get<std::string>();
  };
  // The checkpoint's state is internal to the version that wrote it (docs/contracts.md): another
  // version's resume refuses, before any device opens, rather than read it (a review).
  const std::string software = str("software", "");
  const std::string mine = std::string("rig ") + RIG_VERSION;
  if (!software.empty() && software != mine)
    throw ConfigError(path + ": field 'software': the run was started by \"" + software + "\", this is " + mine +
                      ": only the same version resumes a run (its checkpoint is that version's); finish it with that "
                      "version or start a new run");
  // Every field is one this rig writes (checked after the version: a newer rig may write more);
  // an unknown one is a hand edit or another program's.
  static const std::set<std::string> kFields = {"plant",   "hardware",   "serial", "profile", "profile_source",
                                                "software", "started", "no_history", "db", "faults", "profile_digest",
                                                "profile_folder", "history_db", "station"};
  for (const auto& [key, v] : inv.items())
    if (!kFields.count(key)) throw ConfigError(path + ": field '" + key + "': not a field rig writes");
  (void)str("profile", "");  // its type here; its value against profile.toml's once that is read
  (void)str("profile_source", "");
  (void)str("profile_digest", "");
  (void)str("profile_folder", "");
  a.plant = str("plant", "emulated");
  a.hardware = str("hardware", "");
  a.station = str("station", "");
  a.serial = str("serial", "");
  if (a.plant != "emulated" && a.plant != "hardware")
    throw ConfigError(path + ": field 'plant': \"" + a.plant + "\" is neither \"emulated\" nor \"hardware\"");
  if (a.plant == "hardware" && a.hardware.empty())
    throw ConfigError(path + ": field 'hardware': a hardware run must name its hardware file");
  if (a.plant == "hardware" && path_kind(a.hardware, path + ": field 'hardware':") != PathKind::file)
    throw ConfigError(path + ": field 'hardware': " + a.hardware + " does not exist");
  if (a.plant == "emulated" && !a.hardware.empty())
    throw ConfigError(path + ": field 'hardware': \"" + a.hardware + "\", but the run is on the emulated plant");
  // The emulated plant's injected sample losses (--inject drop@SEQ:COUNT) are part of the
  // device's history: the resume's replay and its remaining phases see them again, so the resumed
  // passport is the uninterrupted run's (without them the replay differed and the warning blamed
  // another build: a review). Signals and e-stops are never repeated.
  if (inv.contains("faults")) {
    const nlohmann::json& f = inv["faults"];
    if (!f.is_array()) throw ConfigError(path + ": field 'faults': expected an array, found " + f.type_name());
    for (const auto& x : f) {
      if (!x.is_string() || x.get<std::string>().rfind("drop@", 0) != 0)
        throw ConfigError(path + ": field 'faults': " + x.dump() + " is not a sample loss (drop@SEQ:COUNT)");
      a.inject.push_back(x.get<std::string>());
    }
    if (a.plant != "emulated") throw ConfigError(path + ": field 'faults': only an emulated run has injected faults");
  }
  if (inv.contains("started") && !inv["started"].is_string())
    throw ConfigError(path + ": field 'started': expected a string, found " + inv["started"].type_name());
  // The start the passport, JUnit and history give the run: the form rig writes, and not after
  // this resume (a review: "garbage" and a start in 2030 went into a PASS passport and the
  // history, and report.html was not written). A day's slack: a station's clock stepped back
  // by NTP, or a run moved from a station whose clock ran fast, must still resume (a code review).
  if (inv.contains("started")) {
    const std::string s = inv["started"].get<std::string>();
    const auto t = history::parse_iso8601(s);
    if (!t || history::normalize_iso8601(s) != s)
      throw ConfigError(path + ": field 'started': \"" + shown_text(s) + "\" is not a UTC time as rig writes it (" +
                        iso8601_utc_now() + ")");
    if (*t > static_cast<long long>(std::time(nullptr)) + 86400) {
      // A station whose clock ran more than a day fast when the run began (then corrected by NTP)
      // wrote run.json at that start by the same clock, so its file time agrees with 'started':
      // that run resumes, said so (a technician's review: the abort advised the resume, which was
      // refused, and every recording was lost). A field changed afterwards has no such witness.
      struct stat st {};
      const bool ec = ::stat(path.c_str(), &st) != 0;
      const long long file_s = ec ? 0 : static_cast<long long>(st.st_mtime);
      if (ec || std::llabs(file_s - *t) > 600)
        throw ConfigError(path + ": field 'started': " + s + " is later than this station's clock (" + iso8601_utc_now() +
                          ") by more than a day, and run.json's own file time (" +
                          (ec ? std::string("unreadable") : iso8601_utc(static_cast<std::time_t>(file_s))) +
                          ") does not witness that start (a copy that did not keep file times, or the field changed "
                          "after the run wrote it); nothing done. If this station's clock was that far ahead when the "
                          "run began, give run.json that time (touch -d " + s + " run.json) and resume");
      std::cerr << "rig: warning: " << path << ": the run started at " << s << " by this station's clock, later than "
                << "its clock now (" << iso8601_utc_now() << "): the clock was wrong then or is now; the passport and "
                << "the history keep that start time\n";
    }
  }
  // The history the run was started with, unless the resume names its own (--db, --no-history):
  // a resume without them recorded its PASS in the default database, the ABORTED row left in
  // the station's (an integrator's review). Older run.json files have neither field.
  if (inv.contains("no_history") && !inv["no_history"].is_boolean())
    throw ConfigError(path + ": field 'no_history': expected true or false, found " + inv["no_history"].type_name());
  const std::string given_db = str("db", "");
  // Where a run without --db recorded, as it resolved at its start (the hardware file's [history],
  // $RIG_HISTORY, the rig config, the default): a resume from a shell without the station's
  // RIG_HISTORY recorded its PASS elsewhere, the ABORTED row kept for good, without a word (a line
  // integrator's review). Older run.json files have neither field.
  const std::string resolved_db = given_db.empty() ? str("history_db", "") : std::string();
  const std::string db = given_db.empty() ? resolved_db : given_db;
  const bool run_records = !inv.value("no_history", false);
  // Where the run records: run.json's --db or history_db, or (neither there, an older run.json)
  // whichever database applied where it ran, which run.json does not say.
  const std::string runs_db =
      db.empty() ? std::string("the database it started with (run.json names none: the default, $RIG_HISTORY or the "
                               "rig config's)")
                 : db;
  a.record_command = db.empty() ? "rig history --record " + shell_word(a.resume)
                                : "rig history --db " + shell_word(db) + " --record " + shell_word(a.resume);
  if (history::password_masked(db))
    a.record_command += " (the password as *** is yours to give, or keep it in ~/.pgpass)";  // a review copied it
  if (run_records && a.no_history) {
    a.history_owed = true;
    a.history_left_behind = fmt::format(
        "the run records into {} (run.json): with --no-history this resume's ending is not recorded there (a row "
        "the run has there keeps its earlier ending); a verdict (PASS, FAIL) is owed: {} lists `history` until rig "
        "run --resume {} or {} records it",
        runs_db, kEndingPending, shell_word(a.resume), a.record_command);
  } else if (run_records && !a.db.empty() && !db.empty() && !history::same_database(a.db, db)) {
    a.history_left_behind = fmt::format(
        "the run records into {} (run.json); this resume records its ending into --db {}: {} keeps the earlier "
        "ending ({} brings it up to date)",
        db, history::mask_password(a.db), db, a.record_command);
  }
  if (!a.db.empty() || a.no_history) return;
  if (inv.value("no_history", false)) {
    a.no_history = true;
  } else if (!resolved_db.empty() && history::password_masked(resolved_db)) {
    a.run_history_db = resolved_db;  // the resume's own resolution may carry the password: compared later
  } else if (!db.empty()) {
    if (history::password_masked(db))  // stored masked
      throw ConfigError(path + ": the run was started with --db " + db + ", whose password run.json does not keep: "
                        "give the same --db with --resume (or --no-history)");
    a.db = db;
    a.db_from_run_json = true;
  }
}

// Where the operator reads the questions: stderr, or the controlling terminal when stderr goes to
// a file (a technician's `rig run ... > run.txt 2>&1` waited on questions only the file held,
// a review); null without either.
std::ostream* prompt_out() {
  if (::isatty(STDERR_FILENO)) return &std::cerr;
  static std::ofstream tty("/dev/tty");
  return tty.is_open() ? &tty : nullptr;
}

// On stderr (prompt_out), as the plan and the progress: stdout carries only the passport table, for scripts.
// The signals are taken by SignalWatcher's thread (blocked here), so a plain read of the answer
// never returned on Ctrl-C: the prompt kept waiting, and a "y" typed after it powered the DUT
// (a technician's review). stdin is polled, and a signal ends the prompt as it ends a run.
// The line is read from the descriptor byte by byte: a buffered reader could hold the next
// answer where poll() does not see it.
// An answer is y or yes, n or no (any case, blanks around), or Enter (the default, no); anything
// else is asked again: "yet to fasten" confirmed a mount, and run.log said "yes" (a review).
bool confirm(const std::string& question, const CancelToken& cancel) {
  std::ostream& out = *prompt_out();
  out << question << " [y/N] " << std::flush;
  std::string line;
  for (;;) {
    cancel.throw_if_requested();
    pollfd in{STDIN_FILENO, POLLIN, 0};
    const int r = ::poll(&in, 1, 50);
    if (r < 0 && errno != EINTR) return false;
    if (r <= 0) continue;
    cancel.throw_if_requested();
    char c = 0;
    const ssize_t n = ::read(STDIN_FILENO, &c, 1);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;  // end of input: no answer is a no
    if (c != '\n') {
      line += c;
      continue;
    }
    const auto first = line.find_first_not_of(" \t\r"), last = line.find_last_not_of(" \t\r");
    std::string word = first == std::string::npos ? "" : line.substr(first, last - first + 1);
    for (char& ch : word) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (word == "y" || word == "yes") return true;
    if (word.empty() || word == "n" || word == "no") return false;
    out << "Answer y (yes) or n (no). " << question << " [y/N] " << std::flush;
    line.clear();
  }
}

// Operator prompts where a person must act; --yes skips them (automation). Returns what the
// operator confirmed, for run.log. planned_s: the plan's device time (the phases' own
// estimates, the table's timing included).
std::vector<std::string> operator_prompts(const RunArgs& a, const acceptance::Profile& p, double planned_s,
                                          std::size_t kept, const CancelToken& cancel) {
  if (a.yes) return {};
  if (!::isatty(STDIN_FILENO) || !prompt_out()) {
    if (a.plant == "emulated") return {};  // nothing to mount: unattended emulated runs need no confirmation
    throw ConfigError("operator confirmation needed (mount the DUT, confirm the table is clear): run with --yes "
                      "for unattended runs");
  }
  // What the answers start: the operator agrees to it, not to a question alone. A run typed
  // without --hardware measures the emulated plant: said first, in capitals, since its passport
  // passes under the serial typed (a technician's review).
  std::ostream& out = *prompt_out();
  if (a.plant == "emulated")
    out << "EMULATED PLANT: no device on the bench is touched; the DUT, the table and the GPIO are simulated "
           "and the passport describes the simulation (give --hardware FILE to test a real DUT).\n";
  out << fmt::format(
      "Profile '{}': {}\nDevice time {}{}. After your answers rig powers the DUT, homes the table and turns it between "
      "U10 ({:g} deg) and U20 ({:g} deg); Ctrl-C at any point stops the table and powers the DUT off.\n",
      p.name, p.description, TerminalView::hms(planned_s), kept ? fmt::format(" left ({} phases complete)", kept) : "",
      p.u10_deg, p.u20_deg);
  std::vector<std::string> confirmed;
  auto ask = [&](const std::string& question, const char* declined) {
    // What a "no" leaves, and what to do next (it said only who declined: a technician's review).
    if (!confirm(question, cancel))
      throw AbortedError(std::string(declined) + ": nothing was powered or moved; give the same command again when ready");
    confirmed.push_back(question);
  };
  ask("Is the DUT mounted on the table with its connector fastened?", "operator did not confirm the DUT is mounted");
  if (!a.serial.empty())
    ask("Is the serial number on the DUT's label " + a.serial + "?", "operator did not confirm the serial number");
  ask("Is the table clear of tools, cables and hands?", "operator did not confirm the table is clear");
  return confirmed;
}

// A DUT without a command channel ([dut] commands = false; emulated: [plant.firmware] commands
// = false) cannot report its serial: the operator gives it, and a run without one is refused
// with the configuration, before any device opens.
void check_serial_source(const RunArgs& a, const toml::table& hw, const toml::table& plant_cfg) {
  if (!a.serial.empty()) return;
  const toml::table* t = a.plant == "hardware" ? cfg::get_table(hw, "dut", true) : cfg::get_table(plant_cfg, "firmware");
  if (!t) return;
  const bool commands = a.plant == "hardware" ? link::link_options(*t).commands : plant::firmware_options(t).commands;
  if (commands) return;
  throw ConfigError(cfg::where(*t->get("commands")) + ": " + (a.plant == "hardware" ? "[dut]" : "[plant.firmware]") +
                    " commands = false: the DUT cannot report its serial; give it with --serial");
}

// A DBC-described stream's rate is the hardware file's (given, or [dut.stream]'s default): a run
// at the profile's rate over a stream at another labels every capture with the wrong rate and
// scales every tau (a review: [dut.stream] rate_hz = 500 under a 1000 Hz profile, dry run exit 0;
// with commands the DUT said so only after power-on, and without them never). The rig protocol's
// DUT declares its rate at bring-up, checked there.
// (`stream`: the hardware file's layout, null for the rig protocol and on the emulated plant, whose
// [plant.firmware] the plant checks itself.)
void check_stream_rate(const RunArgs& a, const std::shared_ptr<const link::DbcStreamDecoder>& stream,
                       const acceptance::Profile& p) {
  if (!stream || std::abs(stream->rate_hz() - p.rate_hz) <= 1e-6 * p.rate_hz) return;
  const auto& kw = stream->spec().key_where;
  const auto at = kw.find("rate_hz");
  throw ConfigError(fmt::format("{}: the DUT streams at {} Hz, but profile '{}' ({}) records at rate_hz = {} Hz: every "
                                "capture would be labelled with the profile's rate and every tau scaled by {:.6g}; "
                                "rate_hz must be the rate the DUT streams at: run it with a profile that records at "
                                "that rate",
                                at != kw.end() ? at->second + ": rate_hz = " + fmt::format("{}", stream->rate_hz())
                                               : a.hardware + ": [dut.stream] gives no rate_hz (the default)",
                                stream->rate_hz(), p.name, shown_text(p.source), p.rate_hz,
                                p.rate_hz / stream->rate_hz()));
}

// The procedure's U10 and U20 angles within the table's travel, where the rig knows the travel
// before the table opens: a CiA 402 drive map's [limits] on hardware, [plant.table]'s limits on
// the emulated plant (a rig-v1 drive reports its limits once connected, and its move refuses
// then). A run with an angle outside refused at its first U20 move, after devices opened and
// run01 was recorded (a review).
void check_procedure_angles_in_travel(const RunArgs& a, const toml::table& hw, const toml::table& plant_cfg,
                                      const acceptance::Profile& p) {
  double lo = 0, hi = 0;
  std::string whose;
  if (a.plant == "hardware") {
    const toml::table* t = cfg::get_table(hw, "table");
    if (!t || modbus::table_drive(*t) != "cia402") return;
    const modbus::DriveMap map = modbus::table_drive_map(*t);
    lo = map.limit_neg_deg, hi = map.limit_pos_deg;
    whose = "drive map " + map.path + " [limits]";
  } else {
    const toml::table* pt = cfg::get_table(plant_cfg, "table");
    const plant::TableParams tp = plant::table_params_from_toml(pt);
    lo = tp.limit_neg_deg, hi = tp.limit_pos_deg;
    whose = "the emulated table's [plant.table] limit_neg_deg / limit_pos_deg";
  }
  // Where the angle was written: the hardware file's [procedure], else the profile file's [table]
  // (a review: the message named the profile without a line, and advised [procedure], which a
  // profile does not have).
  const toml::table* mount = a.plant == "hardware" ? cfg::get_table(hw, "procedure") : nullptr;
  std::optional<toml::table> profile_file;
  if (!mount) {
    try {  // a built-in profile's text has lines too (it said "builtin:ci:" with none, a review)
      profile_file = p.source.rfind("builtin:", 0) == 0
                         ? cfg::parse_string(acceptance::builtin_profile_text(p.source.substr(8)), p.source)
                         : cfg::parse_file(p.source);
    } catch (const std::exception&) {  // read once already; only the line is lost
    }
  }
  const toml::table* written = mount ? mount : profile_file ? cfg::get_table(*profile_file, "table") : nullptr;
  // What to change: on hardware a mount's angles go in the hardware file's [procedure] (a built-in
  // profile cannot be edited, and the advice named only it: a bring-up review); a built-in
  // profile's angles are changed by a profile file based on it.
  const bool builtin = p.source.rfind("builtin:", 0) == 0;
  const std::string change =
      mount ? std::string("change the hardware file's [procedure] u10_deg / u20_deg or the limits")
      : a.plant == "hardware"
          ? std::string("set the mount's angles in the hardware file's [procedure] u10_deg / u20_deg (used over the "
                        "profile's), or change ") +
                (builtin ? "the limits" : "the profile's [table] u10_deg / u20_deg or the limits")
          : builtin ? fmt::format("change the limits, or the angles in a profile file (base = \"{}\", [table] u10_deg / "
                                  "u20_deg)",
                                  p.source.substr(8))
                    : std::string("change the profile's [table] u10_deg / u20_deg or the limits");
  for (const auto& [key, deg] : {std::pair{"u10_deg", p.u10_deg}, {"u20_deg", p.u20_deg}})
    if (deg < lo || deg > hi) {
      const toml::node* at = written ? written->get(key) : nullptr;
      throw ConfigError(fmt::format("{}: {} = {:g}°: outside the table's travel [{:g}°, {:g}°] ({}): the procedure "
                                    "could not turn the DUT there; {}",
                                    at ? cfg::where(*at) : shown_text(p.source), key, deg, lo, hi, whose, change));
    }
}

// On hardware the DUT's rate is read at bring-up (after power-on); the emulated DUT's is known
// from the profile's [plant], so a profile it cannot run is refused here, --dry-run included.
void check_emulated_rate(const toml::table& profile_table, const std::string& source, const acceptance::Profile& p,
                         double dut_rate_hz) {
  if (std::abs(dut_rate_hz - p.rate_hz) <= 1e-6 * p.rate_hz) return;
  const std::string why = fmt::format("the emulated DUT streams at {:g} Hz", dut_rate_hz);
  if (const toml::node* n = profile_table.at_path("procedure.rate_hz").node()) cfg::reject(*n, "rate_hz", why);
  throw ConfigError(fmt::format("{}: rate_hz = {:g}: {}", source, p.rate_hz, why));
}

// What the DUT can be asked, from the hardware file's [dut] or the emulated plant's [plant.firmware],
// read once per run (each reading parses the DBC): and on hardware the stream's layout.
struct DutLinkOptions {
  acceptance::DutAbilities can;
  std::shared_ptr<const link::DbcStreamDecoder> stream;  // hardware with a DBC-described stream
};
DutLinkOptions dut_link_options(const RunArgs& a, const toml::table& hw, const toml::table& plant_cfg) {
  if (a.plant == "hardware") {
    const link::LinkOptions o = link::link_options(*cfg::get_table(hw, "dut", true));
    return {{o.commands, o.loop_test, link::loop_test_refused_by(o)}, o.stream};
  }
  // The emulated link takes the firmware's command channel and asks the firmware for the loop
  // test (plant/emulated/world.cpp): a firmware without one refuses it over the bus.
  const plant::FirmwareOptions o = plant::firmware_options(cfg::get_table(plant_cfg, "firmware"));
  link::LinkOptions lo;
  lo.commands = o.commands;
  return {{o.commands, o.loop_test, link::loop_test_refused_by(lo)}, nullptr};
}

// What the plan cannot do on this DUT, said before the run (the run says it again, with the
// passport's `skipped`): the DUT's link options, or on the emulated plant its firmware's.
std::vector<std::string> planned_skips(const RunArgs& a, const toml::table& hw, const acceptance::DutAbilities& can,
                                       const acceptance::Profile& p) {
  const bool commands = can.commands, loop_test = can.loop_test;
  std::vector<std::string> out;
  if (!commands) {
    out.push_back("identify: the DUT has no command channel (commands = false); the serial is --serial's");
    out.push_back("set output filter: the DUT has no command channel; y(t) is whatever filter it runs");
  }
  if (!commands || !loop_test) {
    const std::string why = !commands ? "no command channel" : "loop_test = false";
    const bool design = a.plant == "hardware" && acceptance::read_design_model(*cfg::get_table(hw, "dut", true));
    out.push_back("loop test (" + why + "): bandwidth_0p5 and settling_time " +
                  (design ? std::string("from [dut.design], labelled design model")
                          : std::string("null") + (p.limits.count("bandwidth_0p5") || p.limits.count("settling_time")
                                                        ? " (limited: the run will FAIL)"
                                                        : "")));
  }
  return out;
}

// The rig's name from the hardware file's [rig] section, else the host name.
// (load_hardware_file has validated [rig] and [history].)
std::string cfg_station(const toml::table& hw) {
  if (const toml::table* r = cfg::get_table(hw, "rig")) {
    const std::string name = cfg::get_string(*r, "name", std::string());
    if (!name.empty()) return name;
  }
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  return host;
}

// The passport's station: the run's (run.json's, for a resume), else this machine's for the plant.
std::string station_of(const RunArgs& a, const toml::table& hw) {
  if (!a.station.empty()) return a.station;
  return a.plant == "hardware" ? cfg_station(hw) : "emulated plant";
}

// --db, else the hardware file's [history] url, else the rig config's default.
std::string history_url(const RunArgs& a, const toml::table& hw) {
  if (!a.db.empty()) return a.db;
  if (const toml::table* h = cfg::get_table(hw, "history"))
    if (h->contains("url")) {
      // A relative SQLite file is relative to the hardware file, as its dbc and drive map are
      // (it was the working folder's: a resume started elsewhere wrote a new database; a review).
      const std::string url = cfg::get_string(*h, "url");
      const std::optional<std::string> file = history::sqlite_path(url);
      const auto& src = h->get("url")->source().path;
      if (file && fs::path(*file).is_relative() && src)
        return "sqlite:" + (fs::path(*src).parent_path() / *file).lexically_normal().string();
      return url;
    }
  return default_history().url;  // RIG_HISTORY's and the rig config's mistakes named as theirs
}

// Why a run whose log is missing lines has no resume, as `no resume:` says it.
std::string log_missing_lines_why(const std::string& out) {
  return "the run's log " + shown_text(out + "/run.log") + " is missing lines the disk refused";
}

void refuse_a_log_missing_lines(const std::string& dir) {
  constexpr const char* kNoResume = "; no resume gives those lines back, nor a verdict beside them: start a new run "
                                    "with another --out (this folder stays as it was)";
  if (const std::string why = earlier_log_missing_lines(dir); !why.empty())
    throw ConfigError(dir + ": its run ended without a verdict: " + why + kNoResume);
  if (const std::string why = checkpoint_log_missing_lines(dir); !why.empty())
    throw ConfigError(dir + ": its checkpoint records that " + why + kNoResume);
}

// Every attempt's last line in run.log (rig run writes it as it returns, whatever the ending:
// AttemptEnd). An attempt without it was stopped by a kill or a power cut, or the disk refused its
// last lines: a resume says so (earlier_attempt_unended). One line every ending writes, rather
// than a list of each ending's last words, which missed some and took others for none (a review).
constexpr std::string_view kAttemptEnds = "rig run: this attempt ends here";

// The run.log this process opened for its run (make_logger): where AttemptEnd writes.
std::string g_attempt_log;  // NOLINT: one run per process

// Where the last attempt in `dir`'s run.log has no kAttemptEnds line after its first line, the
// time of its last line; "" otherwise. Read before the resume writes its own first line.
std::string earlier_attempt_unended(const std::string& dir) {
  constexpr std::size_t kStamp = 24;  // 2026-12-06T12:09:24.486Z, as make_logger stamps a line
  static const std::regex first(R"(^\S+Z info +rig \S+ run: )");
  std::ifstream in(dir + "/run.log");
  std::string line, last;
  bool ended = true;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    last = line;
    if (std::regex_search(line, first)) ended = false;  // an attempt's first line
    else if (line.ends_with(kAttemptEnds)) ended = true;
  }
  return ended || last.size() < kStamp ? "" : last.substr(0, kStamp);
}

// The resume's second line, where the earlier attempt's account has no end (earlier_attempt_unended).
void say_where_the_account_broke_off(const std::string& unended, spdlog::logger& log) {
  if (!unended.empty())
    log.warn("the earlier attempt's account above ends at {} without its ending (stopped by a kill or a power cut, or "
             "its last lines refused by the disk): what it did after that line is not in this log",
             unended);
}

// `dir`'s .ending-pending as `steps` (one per line), removed when none is left.
void write_pending_steps(const std::string& dir, const std::vector<std::string>& steps) {
  std::string text;
  for (const std::string& st : steps) text += st + "\n";
  std::error_code ec;
  if (text.empty())
    fs::remove(dir + "/" + kEndingPending, ec);
  else
    write_file_atomic(dir + "/" + kEndingPending, text);
}

// The outcome (ABORTED or ERROR) of an earlier attempt's ending whose history row is still owed:
// .ending-pending lists `history` beside a passport that stopped the run. "" otherwise.
std::string owed_interrupted_ending(const std::string& dir) {
  const std::vector<std::string> steps = pending_steps(dir).value_or(std::vector<std::string>{});
  if (std::find(steps.begin(), steps.end(), kStepHistory) == steps.end()) return "";
  // A later ending stopped while writing its files: its list, not the earlier ending's.
  if (std::find(steps.begin(), steps.end(), kStepEnding) != steps.end()) return "";
  const std::string o = passport_outcome(dir).value_or("");
  return o == "ABORTED" || o == "ERROR" ? o : "";
}

// A run stopped while it started (a kill after its run.json, or in its first seal) left only the
// files of its start: its run.json (the rig's: it names the software), profile.toml, staging files,
// at most an empty run.log; no seal, nothing recorded. Neither resumable with the station's key (never sealed) nor
// reusable, that folder was lost (a review); a new run takes it over. (A profile.toml alone may
// be anybody's: refused with the advice to move it, as before.)
bool only_a_start(const std::string& dir) {
  static const std::set<std::string> start = {"profile.toml", "run.json", "profile.toml.tmp", "run.json.tmp",
                                              "seal.json.tmp"};
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (!fs::is_regular_file(fs::symlink_status(e.path(), ec))) return false;
    // A log opened and killed before its first line: empty.
    if (!start.contains(name) && !(name == "run.log" && fs::file_size(e.path(), ec) == 0 && !ec)) return false;
  }
  return !ec && holds_a_rig_run(dir);
}

// A new run never lands on an earlier one, whatever state it stopped in: run.json is written
// before any device opens, checkpoint.json after the first phase, passport.json at every ending
// (a hardware run that could not open its devices has the first and the last, no checkpoint).
// A finished run's folder is left alone; an unfinished one is resumed. Nor does a new run replace
// a file of the name it writes that something else left there (a review: a report.html was
// replaced without a word, where a stray capture is kept aside): the run's outputs, its seals,
// an ending's list, and a profile.toml that is not the profile the run copies there.
std::string taken_over_note(const std::string& dir) {
  return dir + " holds only the start of an earlier run, stopped before its log began (run.json, profile.toml; "
               "nothing recorded): this run takes the folder over";
}

std::string resume_refusal(const std::string& dir);

// True when the folder holds only a stopped start (only_a_start), which the run takes over.
bool refuse_an_earlier_run(const std::string& dir, const std::string& profile_source) {
  if (only_a_start(dir)) return true;
  const std::string v = verdict_of(dir);
  if (!v.empty()) throw ConfigError(dir + " holds a finished run (its passport says " + v + "): choose another --out");
  std::error_code ec;
  // Only a folder with run.json can be resumed (it holds the invocation a resume repeats).
  const bool resumable = fs::exists(fs::path(dir) / "run.json", ec);
  for (const char* f : {"checkpoint.json", "run.json", "passport.json"})
    if (fs::exists(fs::path(dir) / f, ec)) {
      // Its resume offered only where it would start (a technician's review: "start a new run",
      // then here "use --resume", which was refused again).
      const std::string no_resume = resumable ? resume_refusal(dir) : "";
      throw ConfigError(dir + " holds an earlier run (" + f + "): " +
                        (!resumable           ? std::string("choose another --out")
                         : no_resume.empty() ? "use --resume " + dir + " or another --out"
                                             : "choose another --out (it has no resume: " + no_resume + ")"));
    }
  // (A folder in such a place is refuse_non_files' to name.)
  auto there = [&](const fs::path& f) {
    const fs::file_status st = fs::symlink_status(f, ec);
    return fs::exists(st) && !fs::is_directory(st);
  };
  std::vector<std::string> would_replace;
  for (const std::string f : {"junit.xml", "analysis.json", "report.html", "seal.json", "seal.prev.json", kEndingPending,
                              "run.log", acceptance::kLoopTestFile})
    if (there(fs::path(dir) / f)) would_replace.push_back(f);
  // And the staging names the rig writes them through: a file there is removed by the first write
  // (a review: a passport.json.tmp of the user's went without a word). Its contents only: a FIFO
  // or a link there holds none, and is replaced unopened as before.
  for (const std::string f : {"passport.json", "junit.xml", "analysis.json", "report.html", "checkpoint.json", "run.json",
                              "seal.json", kEndingPending})
    if (fs::is_regular_file(fs::symlink_status(fs::path(dir) / (f + ".tmp"), ec))) would_replace.push_back(f + ".tmp");
  // Nor a run's records left by something else: appended to (run.log) or set aside under the
  // rig's own name for its interrupted attempts (a review: a planted run01-U10.cap became
  // run01-U10.cap.interrupted-1, which the seal then vouched for as the run's own).
  if (fs::is_directory(fs::path(dir) / "captures", ec))
    for (const auto& e : fs::directory_iterator(fs::path(dir) / "captures", ec))
      if (there(e.path())) would_replace.push_back("captures/" + e.path().filename().string());
  const fs::path profile = fs::path(dir) / "profile.toml";
  if (there(profile) &&
      (profile_source.rfind("builtin:", 0) == 0 || !fs::equivalent(profile, profile_source, ec)))
    would_replace.emplace_back("profile.toml");
  if (!would_replace.empty())
    throw ConfigError(fmt::format("{} holds {}, which a run writes, but no run (no run.json): a new run would replace "
                                  "{}; move {} or choose another --out",
                                  dir, fmt::join(would_replace, ", "), would_replace.size() == 1 ? "it" : "them",
                                  would_replace.size() == 1 ? "it" : "them"));
  return false;
}

// The history the run will record into, checked as far as it can be without writing: a URL of
// the right form; an SQLite file that exists must be a database (junk bytes passed, and the run's
// row was lost at its end, logged only: a review), one that does not must be creatable in a
// writable folder. A PostgreSQL server is reached when the run records (it may be down now).
// `resume`: the advice for a lock leaves out a new run's --no-history (a resume's own follows).
void check_history_can_record(const std::string& url, bool resume) {
  const std::optional<history::SqliteFile> f = history::sqlite_file(url);
  if (!f) return;
  const std::string& file = f->path;
  const std::string shown = "history database " + file;
  std::error_code ec;
  if (f->exists) {
    if (!fs::is_regular_file(file, ec)) throw ConfigError(shown + ": not a regular file");
    // Read and written, its folder taking SQLite's journal beside it (one rig may read but not
    // write, owned by another account: the row was lost at the run's end; a code review).
    const fs::path folder = fs::absolute(file, ec).parent_path();
    if (::access(file.c_str(), R_OK | W_OK) != 0)
      throw ConfigError(shown + ": cannot be written: " + std::strerror(errno));
    if (!can_create_file_in(folder))
      throw ConfigError(shown + ": its folder " + folder.string() + " takes no new file (SQLite's journal goes there)");
    try {
      history::open_db(url, history::Access::ReadOnly)->has_table("runs");  // reads its header
    } catch (const history::LockedError& e) {
      // A lock held past the busy timeout is not a damaged file (a review: it read "not a
      // database rig can open"): db.cpp's words for it (how long, read or write), named as here.
      throw history::LockedError(shown, e.reason + (resume ? std::string()
                                                           : " (a new run may also run with --no-history and be "
                                                             "recorded later with `rig history --record DIR`)"));
    } catch (const ConfigError& e) {
      throw ConfigError(shown + ": not a database rig can open (" + e.what() + ")");
    }
    return;
  }
  const fs::path p = nearest_existing(fs::absolute(file, ec).parent_path());
  if (!fs::is_directory(p, ec) || !can_create_file_in(p))
    throw ConfigError(shown + ": cannot be created (" + p.string() + " is not a writable folder)");
  history::refuse_a_new_database_without_its_folder(url);
}

// The plan's device time: every phase's own estimate, the table's timing included.
double planned_device_s(const std::vector<Phase>& phases) {
  double total = 0;
  for (const Phase& ph : phases) total += ph.planned_s;
  return total;
}

// The nearest existing ancestor of the run folder must take a new file. access() says yes to root
// on any directory of a writable mount, /proc's included; a file actually made there does not.
// O_TMPFILE makes one with no name, gone at close (nothing touched); a filesystem without it gets
// a named probe, removed at once. The run and its dry run say it alike, before the disk's room (a
// run into /proc was told "0 MB free", its dry run "not writable": a review).
void refuse_an_unwritable_place(const std::string& dir, const std::string& option) {
  std::error_code ec;
  const fs::path p = nearest_existing(fs::absolute(dir, ec));
  if (fs::is_directory(p, ec) && !can_create_file_in(p))
    throw ConfigError(option + " " + dir + ": the run folder is not writable (" + p.string() + ")");
}

// --dry-run touches nothing, yet says whether the run could write its folder: the nearest
// existing ancestor of --out must be a directory this process may write into, and a new run
// must not land on an earlier one (the checks prepare_run_folder and do_run make for real).
// True when the run would take over a stopped start there (refuse_an_earlier_run).
bool check_run_folder(const std::string& dir, bool new_run_here, const std::string& option,
                      const std::string& profile_source) {
  std::error_code ec;
  refuse_a_name_too_long(dir, option);
  const fs::path p = nearest_existing(fs::absolute(dir, ec));
  if (!fs::is_directory(p, ec))
    throw ConfigError(option + " " + dir + ": cannot create the run folder: " + p.string() + " is not a directory");
  refuse_an_unwritable_place(dir, option);
  return new_run_here && refuse_an_earlier_run(dir, profile_source);
}

// The paths the run writes into its JSON files (run.json, passport.json, the history row) must be
// UTF-8 text, as JSON is: a folder named in Latin-1 ran all its phases and then lost the run,
// its passport, JUnit report and history row refused by the JSON writer, exit 4, and every
// resume the same (a review). Refused before anything is written or opened, exit 2.
void require_utf8_paths(const RunArgs& a) {
  std::error_code ec;
  auto check = [&](const std::string& option, const std::string& given, const std::string& path) {
    const std::size_t at = first_non_utf8(path);
    if (at == std::string::npos) return;
    throw ConfigError(fmt::format("{} {}: {}not UTF-8 text (byte 0x{:02X} at offset {}); the run's passport and "
                                  "run.json are JSON, which holds only UTF-8: rename it or give another path",
                                  option, shown_text(given), path == given ? "" : shown_text(path) + " is ",
                                  static_cast<unsigned char>(path[at]), at));
  };
  // As the passport and the history key them: absolute, links resolved (a link into a Latin-1
  // folder and a relative --db in one were missed, a re-test).
  auto real = [&](const std::string& p) {
    const fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
    return (ec ? fs::absolute(p, ec) : r).string();
  };
  if (!a.resume.empty()) check("--resume", a.resume, real(a.resume));
  else if (!a.out.empty()) check("--out", a.out, real(a.out));
  else check("--out", "(default: runs/ here)", real("."));
  if (!a.hardware.empty()) check("--hardware", a.hardware, real(a.hardware));
  if (!a.profile.empty()) check("--profile", a.profile, a.profile);
  if (!a.db.empty()) {
    check("--db", a.db, a.db);
    if (const std::optional<std::string> file = history::sqlite_path(a.db)) check("--db", a.db, real(*file));
  }
}

// The passport's identity block, for every ending (finished at the time of the call).
PassportInfo passport_info(const RunArgs& a, const acceptance::Profile& p, const toml::table& hw,
                           const std::string& started, const std::string& serial) {
  PassportInfo info;
  info.serial = serial;
  info.profile = p.name;
  info.profile_sha256 = a.profile_sha256;
  info.plant = a.plant;
  info.station = station_of(a, hw);
  info.started = started;
  info.finished = iso8601_utc_now();
  info.software = std::string("rig ") + RIG_VERSION;
  // As the history records it (rig/report/history.cpp): "/x/./run/" was written as given.
  std::error_code ec;
  fs::path dir = fs::weakly_canonical(fs::absolute(a.out), ec);
  if (ec) dir = fs::absolute(a.out).lexically_normal();
  info.out_dir = dir.string();
  return info;
}

// What this run wrote so far that a seal may vouch for (docs/seal.md): its invocation and
// profile, the captures its completed recordings name and the loop test's records; never
// anything else that lies in the folder.
std::vector<std::string> files_of_the_run(const acceptance::DutState& st) {
  std::vector<std::string> f = {"run.json", "profile.toml"};
  for (const std::string& c : st.captures()) f.push_back(c);
  if (st.loop_test && st.loop_test->supported) f.push_back(st.loop_test->file);
  return f;
}

// The records in `dir` its checkpoint does not keep (captures/*.cap, loop-test.csv): what an
// interruption left partial, set aside as NAME.interrupted-N when its phase records again.
std::vector<std::string> partial_records(const std::string& dir, const acceptance::DutState& st) {
  const std::vector<std::string> kept = files_of_the_run(st);
  std::vector<std::string> candidates = {acceptance::kLoopTestFile};
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "captures", ec))
    if (e.path().extension() == ".cap") candidates.push_back("captures/" + e.path().filename().string());
  std::vector<std::string> partial;
  for (const std::string& f : candidates)
    if (fs::is_regular_file(fs::symlink_status(fs::path(dir) / f, ec)) &&
        std::find(kept.begin(), kept.end(), f) == kept.end())
      partial.push_back(f);
  std::sort(partial.begin(), partial.end());
  return partial;
}

// The run's records that are no longer in its folder (removed while the run went on: a clean-up
// script, a folder deleted by hand; a review ended such a run PASS with its captures and run.log
// gone): the files a seal would vouch for and run.log, the account of the run.
std::vector<std::string> records_gone(const std::string& out, const acceptance::DutState& st) {
  std::vector<std::string> gone;
  std::vector<std::string> files = files_of_the_run(st);
  files.emplace_back("run.log");
  for (const std::string& f : files) {
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(out) / f, ec)) gone.push_back(f);
  }
  return gone;
}

// The run's recordings that are no longer what their writer closed ("FILE (how): problem"):
// truncated, written to or replaced while the run went on. A moved stamp (size, modification
// time, inode) or the loop test's CRC only raises the question: the record is then read as a
// resume reads it (ProcedureState::recording_problem), and only a problem there counts; one that
// holds is `touched` (a touch, a network file system's own times or inodes). The run that wrote
// them judges them as its resume would, as the seal would otherwise vouch for them (a review: a
// capture truncated mid-run ended PASS). With the station's key each record is also held to the
// MAC sealed when it closed: an edit that kept its size and put its modification time back passes
// the stamps (a review).
std::vector<std::string> records_changed(const std::string& out, const acceptance::ProcedureState& state,
                                         const std::optional<seal::Key>& key, std::vector<std::string>& touched) {
  const acceptance::DutState& st = state.slot();
  std::vector<std::string> changed;
  auto judge = [&](const std::string& rel, const std::string& how) {
    if (const std::string problem = state.recording_problem(rel, out); !problem.empty())
      changed.push_back(rel + " (" + how + "): " + problem);
    else
      touched.push_back(rel + " (" + how + ")");
  };
  auto check = [&](const acceptance::Recorded& r) {
    if (!r.written) return;
    const std::optional<FileStamp> now = stamp_of((fs::path(out) / r.capture).string());
    if (!now) return;  // gone: records_gone names it
    if (const std::string how = stamp_change(*r.written, *now); !how.empty()) judge(r.capture, how);
  };
  for (const auto& [index, run] : st.runs) check(run.rec);
  if (st.in_run) check(*st.in_run);
  if (st.raw) check(*st.raw);
  // The loop test's records are small: read whole by the resume's own check (its CRC-32 among it).
  if (st.loop_test && st.loop_test->supported && fs::exists(fs::path(out) / st.loop_test->file))
    if (const std::string problem = state.recording_problem(st.loop_test->file, out); !problem.empty())
      changed.push_back(st.loop_test->file + ": " + problem);
  if (key)
    for (const std::string& u : records_unlike_their_seal(out, *key, files_of_the_run(st))) {
      const std::string rel = u.substr(0, u.find(':'));
      const bool said = std::any_of(changed.begin(), changed.end(), [&](const std::string& c) {
        return c.compare(0, rel.size(), rel) == 0 && (c.size() == rel.size() || c[rel.size()] == ' ' || c[rel.size()] == ':');
      });
      if (!said) changed.push_back(u);
    }
  return changed;
}

// Records the run in its history database; false (logged) when the database is not reachable.
// `earlier`: the outcome of an earlier attempt's ending recorded before this attempt's own (the
// line names it; both said "recorded ... as run N", one run's two endings read as two records).
bool record_in_history(const RunArgs& a, const toml::table& hw, const nlohmann::json& passport,
                       const std::string& out_dir, spdlog::logger& log, const std::string& earlier = {}) {
  try {
    const std::string url = history_url(a, hw);
    const std::optional<history::SqliteFile> file = history::sqlite_file(url);
    const bool fresh = file && !file->exists;
    const history::Recorded rec = history::record_run(url, passport, out_dir);
    // Where it went, said (a newcomer found a row in ~/.local/share/rig/history.sqlite that no
    // output had mentioned); a database this run created too: a typo in --db or [history] url
    // makes one, and the station's history never sees the run (a technician's review).
    const std::string shown = history::mask_password(url);
    const std::string line = fmt::format(
        "{}recorded in the history database {} as run {} (rig history --db {}){}{}",
        earlier.empty() ? "" : "the earlier attempt's " + earlier + " ending ", shown, rec.id, shown,
        earlier.empty() ? "" : "; this attempt's ending goes to the same run's endings",
        fresh ? "; a new database, created by this run: if the station has one, check the URL" : "");
    log.info("{}", line);
    if (!a.quiet) std::cerr << line << "\n";
    // A verdict recorded before and another outcome now (a folder put back to an earlier state
    // and resumed), a copy of the folder resumed elsewhere (it was silent, a review): as
    // `rig history --record` says them.
    for (const std::string& note : history::record_notes(rec, passport)) log.warn("history: {}", note);
    return true;
  } catch (const std::exception& e) {
    // The --record hint names the database (a line integrator's review: as printed it wrote into
    // $RIG_HISTORY's or the default, not the run's); a password is never printed, so a URL that
    // carries one is given again by the user (or kept in ~/.pgpass, which libpq reads).
    const std::string url = history_url(a, hw), shown = history::mask_password(url);
    const std::string record = "rig history --db " + shell_word(shown) + " --record " + shell_word(a.out);
    log.error("history database not updated: {} (the run's resume, or {}, records it{})", e.what(), record,
              shown != url ? "; the password as *** is yours to give, or keep it in ~/.pgpass" : "");
    return false;
  }
}

// A sealed run resumes only with its key: the line that offers the resume names it, as this run
// was given it (a technician's review: the hint, followed as printed, was refused, exit 2). Taken
// from RIG_SEAL_KEY, it is there for the resume too.
std::string resume_key_words(const RunArgs& a, bool sealed) { return sealed ? seal_key_words(a.seal_key) : ""; }

// What every ending of a run leaves: passport.json, junit.xml, analysis.json, report.html and
// the history row (a report or history failure is logged, never the run's outcome).
// The list of what is left (.ending-pending) comes first, then analysis.json and report.html,
// then the passport, and junit.xml is put in place with
// it (staged, then renamed): a CI job reading junit.xml never sees a PASS the folder has no
// passport for, and a folder that cannot take the files (a full disk) is exit 4 with no staged
// file left (the caller then writes the smaller ERROR ending where it fits). What comes after the
// passport (the final seal, the history row, which may wait on a network) is listed in
// .ending-pending until done: a run killed there (a review's kill stress left PASS runs without
// report.html or history row, their resume refused for good) is finished by its resume
// (finish_pending_ending).
nlohmann::ordered_json write_run_outputs(const RunArgs& a, const toml::table& hw, const PassportInfo& info,
                                         const RunResult& res, const MeasurementSet& values,
                                         const acceptance::DutState& dut, const std::optional<seal::Key>& key,
                                         spdlog::logger& log) {
  auto passport = make_passport(info, res, values);
  const nlohmann::json analysis = acceptance::analysis_document(dut);
  const std::string junit = a.out + "/junit.xml", pass = a.out + "/passport.json", pending = a.out + "/" + kEndingPending;
  // What follows the passport, junit.xml's rename first: listed even where nothing else follows
  // (no key, --no-history), so a stop between the two renames leaves a list its resume finishes
  // (a re-test: an earlier ending's junit.xml stayed beside this passport, the run "complete").
  std::string steps = std::string(kStepJunit) + "\n";
  if (key) steps += std::string(kStepSeal) + "\n";
  // A verdict a --no-history resume reached is owed to the run's database; an ABORTED or ERROR
  // ending is not (the run goes on, and owing it would refuse the next --no-history resume for good:
  // a re-test), the row there keeping its earlier ending as before.
  const bool owed = a.history_owed && (res.outcome == RunOutcome::Pass || res.outcome == RunOutcome::Fail);
  if (!a.no_history || owed) steps += std::string(kStepHistory) + "\n";
  bool report_written = true, passport_in_place = false;
  // An earlier ending's list (its history row owed), put back if this ending fails before its
  // passport is in place: the folder is then that ending's still.
  const std::optional<std::vector<std::string>> earlier_list = pending_steps(a.out);
  try {
    // The list first: from analysis.json on, this ending's files stand beside the passport in
    // place until this one replaces it (an earlier ending's, resumed), and a folder without the
    // list reads as final (a kill there left report.html saying PASS beside an ABORTED passport, no
    // list: a review). With the list, a resume finds the ending unfinished and computes it again.
    // Marked as this ending's (`ending`): a resume does not take the list for the earlier ending's
    // (its history row owed) while that ending's passport is still in place (a code review).
    write_file_atomic(pending, std::string(kStepEnding) + "\n" + steps);
    write_file_atomic(a.out + "/analysis.json", analysis.dump(1));
    write_file_staged(junit, junit_xml(info, res, values));
    write_file_staged(pass, passport_text(passport));
    try {
      report::write_report(a.out, passport, analysis);  // the documents in memory, not parsed again
    } catch (const std::exception& e) {
      // A step left for the resume (a review: a full disk ended PASS, exit 0, without the page,
      // the resume said "nothing to resume", and a seal made without it failed `rig verify` for
      // good once `rig report` drew it): the final seal goes on without it, and the resume draws
      // the page and seals again. An earlier ending's page (an ABORTED one, resumed) must not
      // stand beside this passport.
      report_written = false;
      std::error_code gone;
      fs::remove(a.out + "/report.html", gone);
      steps.insert(steps.find('\n') + 1, std::string(kStepReport) + "\n");
      log.error("report.html not written: {} (rig run --resume {}{} writes it{})", e.what(), shell_word(a.out),
                resume_key_words(a, key.has_value()), key ? " and seals it" : "");
    }
    write_file_atomic(pending, steps);  // what follows this passport, the mark gone
    commit_staged(pass);
    passport_in_place = true;
    commit_staged(junit);
  } catch (...) {  // nothing staged is left behind, nor this ending's list beside a passport not its own
    std::error_code ec;
    if (!passport_in_place) try {
        write_pending_steps(a.out, earlier_list.value_or(std::vector<std::string>{}));
      } catch (const std::exception& e) {
        log.error("{} not restored: {}", kEndingPending, e.what());
      }
    for (const std::string& f : {junit, pass}) fs::remove(f + ".tmp", ec);
    throw;
  }
  bool sealed_now = !key, recorded_now = a.no_history && !owed;  // the steps after the passport, as they went
  if (key) {  // without report.html when it could not be written: the resume draws it and seals again
    try {
      std::vector<std::string> files = files_of_the_run(dut);
      // A capture this attempt left partial at its stop is its own record too: sealed as written,
      // so an aborted sealed run verifies (docs/seal.md); a resume sets it aside and records anew.
      for (const std::string& c : dut.partial_captures)
        if (fs::is_regular_file(fs::symlink_status(fs::path(a.out) / c)) &&
            std::find(files.begin(), files.end(), c) == files.end())
          files.push_back(c);
      if (fs::exists(Executive::checkpoint_path(a.out))) files.emplace_back("checkpoint.json");
      for (const char* f : kRunOutputs)
        if (fs::exists(a.out + "/" + f)) files.emplace_back(f);
      seal_run_folder(a.out, *key, files, std::nullopt, to_string(res.outcome));
      drop_previous_seal(a.out);
      sealed_now = true;
      log.info("run folder sealed (seal.json, key {})", key->id);
    } catch (const std::exception& e) {
      // With the way on (a technician's review: the run ended PASS with no word of it), for a
      // verdict alone: its resume computes the ending again from the kept records (no device
      // opened, nothing measured again) and seals it. A stopped run's resume goes on with the run,
      // or is refused (a log missing lines, records changed), as the lines after this one say (a
      // review: the hint came beside `no resume`).
      if (res.outcome != RunOutcome::Pass && res.outcome != RunOutcome::Fail)
        log.error("seal.json not written: {}", e.what());
      else
        log.error("seal.json not written: {} (rig run --resume {}{} seals it: the ending computed again from the "
                  "kept records, nothing measured again)",
                  e.what(), shell_word(a.out), seal_key_words(a.seal_key));
    }
  }
  // The list keeps only what is still to do, rewritten as each step is done (it kept steps
  // already done: a final seal written, and a kill while the history waited on a locked database
  // left "seal" listed; `rig verify` said the ending was not finished, a review).
  std::vector<std::string> listed = pending_steps(a.out).value_or(std::vector<std::string>{});
  const auto keep_only_what_is_left = [&] {
    std::vector<std::string> left;
    if (!report_written) left.emplace_back(kStepReport);
    if (!sealed_now) left.emplace_back(kStepSeal);
    if (!recorded_now) left.emplace_back(kStepHistory);
    if (left == listed) return;
    try {
      write_pending_steps(a.out, left);
      listed = left;
    } catch (const std::exception& e) {  // the longer list stays: a resume finds those steps done
      log.warn("{} not updated: {}", kEndingPending, e.what());
    }
  };
  keep_only_what_is_left();
  if (!a.no_history) recorded_now = record_in_history(a, hw, nlohmann::json::parse(passport.dump()), info.out_dir, log);
  keep_only_what_is_left();
  return passport;
}

// The closing table and the run folder on stdout: a blank line before them on a terminal, where
// the progress lines precede them; none into a pipe or a file, whose first line is then the
// table's (`| head -1` read "": a review).
void say_the_passport(const nlohmann::ordered_json& passport, const std::string& out_dir) {
  std::cout << (::isatty(STDOUT_FILENO) ? "\n" : "") << passport_table(passport) << fmt::format("run folder: {}\n", out_dir);
}

// A run that ends before its devices open (GPIO, table or DUT unreachable, a bad device
// section) still leaves passport.json, junit.xml, analysis.json and report.html, as every
// ending does: outcome ERROR, every measurement UNSET, the reason in aborted_reason. It is
// recorded in the history like any other run.
void write_files_of_unopened_run(const RunArgs& a, const acceptance::Profile& p, const toml::table& hw,
                                 const std::string& started, const std::string& reason, bool config_error,
                                 const std::optional<seal::Key>& key, spdlog::logger& log) {
  acceptance::ProcedureState state(p);
  const std::vector<Phase> phases = acceptance::build_phases(p, state);
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  RunResult res;
  res.outcome = RunOutcome::Error;
  res.message = reason;
  res.config_error = config_error;
  const PassportInfo info = passport_info(a, p, hw, started, a.serial);
  const nlohmann::ordered_json passport = write_run_outputs(a, hw, info, res, values, state.slot(), key, log);
  // The same closing table and OUTCOME line as every other ending (a technician's review: an
  // empty stdout beside an ERROR passport; scripts match "OUTCOME: ERROR").
  say_the_passport(passport, info.out_dir);
}

// The files the rig replaces in a run folder must be files: a folder or a FIFO in their place
// would stop the run after its devices opened (a rename that fails, an open that waits).
void refuse_non_files(const std::string& dir, bool resuming) {
  std::vector<std::string> replaced(std::begin(kRunOutputs), std::end(kRunOutputs));
  replaced.insert(replaced.end(), {"checkpoint.json", acceptance::kLoopTestFile, "seal.json", "seal.prev.json", "run.log"});
  for (const std::string& f : replaced) {
    struct stat st {};
    if (::lstat((dir + "/" + f).c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      throw ConfigError(dir + "/" + f + ": not a regular file; the rig writes its own file there: move this one away" +
                        (resuming && (f == "checkpoint.json" || f == acceptance::kLoopTestFile)
                             ? " (where the run wrote its own there, a resume needs that file back in its place)"
                             : ""));
  }
  // And the captures' folder must be a folder (a file there ended the run ERROR after its devices
  // had opened, a review).
  // Followed: a captures folder on a data disk through a link is a folder; a link to nothing is not.
  struct stat st {};
  if (::lstat((dir + "/captures").c_str(), &st) == 0 &&
      (::stat((dir + "/captures").c_str(), &st) != 0 || !S_ISDIR(st.st_mode)))
    throw ConfigError(dir + "/captures: not a folder; the rig records its captures in it: move this one away");
}

// Whatever its checkpoint holds: a checkpoint of an earlier version can list fewer phases than
// today's procedure has, and its run is complete all the same. For an unsealed folder (a sealed
// one's final seal states the verdict, and a passport it does not vouch for is not read).
// The passport is held to its run first, as `rig report` and `history --record` hold it: another
// run's PASS copied in, or an ABORTED one edited to PASS, was said to "stand" (an integrator's
// review), while report and history refused it.
void refuse_a_final_verdict(const std::string& dir) {
  const std::string v = verdict_of(dir);
  if (v.empty()) return;
  // What does not hold may be an edit, another run's file, or a file moved away or unreadable
  // (junit.xml gone, a newer schema): said as found, with no verdict on the DUT (a code review:
  // "a new run measures the DUT again" was said of a PASS whose junit.xml had been moved).
  const std::string refused = "; so its " + v + " is not taken as this run's: nothing resumed past it, nothing done "
                              "(the folder is as it was; `rig report " + dir + "` holds it to its run the same way)";
  std::string why;
  try {
    why = passport_unlike_its_folder(dir, report::read_passport(dir));
  } catch (const ConfigError& e) {  // the reader's own checks, which name the file
    throw ConfigError(e.what() + refused);
  }
  if (!why.empty()) throw ConfigError(dir + "/passport.json: " + why + refused);
  throw ConfigError(dir + ": the run is complete (its passport says " + v + "): nothing to resume; its passport stands");
}

// The resume's history elsewhere (RunArgs::history_left_behind) is said also under --quiet, which
// keeps only errors on stderr: a line's harness runs quiet and must see it (a re-test).
void say_history_left_behind(const RunArgs& a, spdlog::logger& log) {
  if (a.history_left_behind.empty()) return;
  log.warn("{}", a.history_left_behind);
  if (a.quiet) std::cerr << "rig: warning: " << a.history_left_behind << "\n";
}

// Lines of run.log the disk refused: the first refusal's reason and time (UTC). The run's account
// is one of its records: a verdict whose log is missing lines is no verdict (no_resume_why).
struct LogLoss {
  mutable std::mutex m;
  std::size_t lines = 0;  // refused so far
  std::string why, first;
  std::string said() const {
    const std::lock_guard lock(m);
    return lines ? fmt::format("{}: the disk refused {} line(s), the first at {} ({})", kLogMissingLines, lines, first, why) : "";
  }
};

// Now in UTC to the millisecond, as run.log stamps its lines.
// Seconds and milliseconds from one reading of the clock (two readings put a stamp taken at a
// second's turn almost a second early).
std::string utc_now_ms() {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count();
  const std::string s = iso8601_utc(static_cast<std::time_t>(ms / 1000));  // ...THH:MM:SSZ
  return fmt::format("{}.{:03d}Z", s.substr(0, s.size() - 1), ms % 1000);
}

// A run.log this process cannot open: found before anything started, as a run folder that is not
// writable is (main: exit 2).
struct RunLogUnopened : ConfigError {
  using ConfigError::ConfigError;
};

// The console's log lines on a terminal clear the line first: the progress bar is drawn in place
// without a newline, and an error line was glued onto it ("wall 00:00:032026-...Z error aborted:
// SIGINT received", a technician's review). The bar is drawn again at its next update.
class ConsoleSink final : public spdlog::sinks::stderr_color_sink_mt {
 public:
  void log(const spdlog::details::log_msg& msg) override {
    if (tty_ && should_log(msg.level)) std::fputs("\r\033[K", stderr);
    spdlog::sinks::stderr_color_sink_mt::log(msg);
  }

 private:
  const bool tty_ = ::isatty(STDERR_FILENO) != 0;
};

std::shared_ptr<spdlog::logger> make_logger(const std::string& out_dir, bool quiet,
                                            std::shared_ptr<LogLoss> loss = std::make_shared<LogLoss>()) {
  std::shared_ptr<spdlog::sinks::basic_file_sink_mt> file;
  try {
    file = std::make_shared<spdlog::sinks::basic_file_sink_mt>(out_dir + "/run.log", false);
  } catch (const spdlog::spdlog_ex& e) {  // "Failed opening file X for writing: <the system's reason>"
    const std::string said = e.what();
    const std::size_t colon = said.rfind(": ");
    throw RunLogUnopened(fmt::format("{}/run.log: cannot be opened to write the run's account ({})", out_dir,
                                    colon == std::string::npos ? said : said.substr(colon + 2)));
  }
  g_attempt_log = out_dir + "/run.log";  // only once open: an attempt that never wrote there closes nothing
  file->set_level(spdlog::level::debug);
  auto err = std::make_shared<ConsoleSink>();
  err->set_level(quiet ? spdlog::level::err : spdlog::level::warn);
  // The console first: a sink that throws (run.log on a full disk) ends the logger's loop over
  // its sinks, and the console then lost the line too. The failure said once, as rig says
  // warnings, not spdlog's "[*** LOG ERROR #0001 ***]" (a technician's review).
  auto log = std::make_shared<spdlog::logger>("rig", spdlog::sinks_init_list{err, file});
  log->set_error_handler([out_dir, loss](const std::string& msg) {
    {
      const std::lock_guard lock(loss->m);
      if (loss->lines++ > 0) return;
      loss->why = msg;
      loss->first = utc_now_ms();
    }
    // What it costs, said now: the run goes on for hours after it (a technician's review read
    // "while that lasts" as passing).
    std::cerr << "rig: warning: " << out_dir << "/run.log: a line could not be written (" << msg
              << "); the run's log is short of what follows while that lasts, and a run whose log misses lines "
                 "before its verdict ends ERROR, with no resume (what it records is kept)\n";
  });
  log->set_level(spdlog::level::debug);
  // UTC, marked so, as every other time the run writes (passport, run.json, history): local
  // time without its zone could not be put beside them (an integrator's review).
  log->set_pattern("%Y-%m-%dT%H:%M:%S.%eZ %^%-5l%$ %v", spdlog::pattern_time_type::utc);
  log->flush_on(spdlog::level::debug);
  return log;
}

// The run's logger (make_logger), or a run.log that cannot be opened (a file made immutable, a
// permission taken away, too many open files) said as what it means for the run: `what` (it did
// not start) and how to go on; exit 2, as a run folder found not writable. It said only spdlog's
// "Failed opening file ... for writing", exit 4. (refuse_a_run_log_it_cannot_write finds most
// before the operator is asked anything; this is what is left: a new run's log, a race.)
std::shared_ptr<spdlog::logger> run_log_or_say(const RunArgs& a, const std::shared_ptr<LogLoss>& loss,
                                               const std::string& what, const std::string& resume_key) {
  try {
    return make_logger(a.out, a.quiet, loss);
  } catch (const RunLogUnopened& e) {
    throw RunLogUnopened(fmt::format("{}: {}; to continue once it can be written: rig run --resume {}{}", e.what(), what,
                                    shell_word(a.out), resume_key));
  }
}

// A run stopped after its passport was in place, before the rest of its ending (.ending-pending,
// write_run_outputs): its outcome is final (final_outcome_of: a verdict, or an ending with no
// resume), so nothing is measured or computed again; what is missing is done: a staged junit.xml
// put in place, report.html drawn if it is not there, the history row recorded (the same row,
// under the same id). A sealed run finishes here only when its final seal is written
// (`final_seal`); before it, its resume computes the ending again.
// The passport's exit code; nullopt when there is no such ending. A dry run says what it would do.
std::optional<int> finish_pending_ending(const RunArgs& a, const toml::table& hw, const std::optional<seal::Key>& key,
                                         bool final_seal, const MeasurementSet& declared) {
  const std::string dir = a.out, pending = a.out + "/" + kEndingPending;
  std::error_code ec;
  if (!fs::exists(pending, ec)) return std::nullopt;
  const std::vector<std::string> steps = pending_steps(dir).value_or(std::vector<std::string>{});
  // An ending stopped before its passport's rename: the passport in place is not its verdict,
  // so the ending is computed again.
  if (std::find(steps.begin(), steps.end(), kStepEnding) != steps.end()) return std::nullopt;
  const bool sealed = key.has_value();
  const std::string v = final_outcome_of(dir);
  if (v.empty() || (sealed && !final_seal)) return std::nullopt;
  // How the run stands, as each line below says it: a verdict is complete; an ending without one
  // stopped the run for good.
  const bool verdict = is_verdict(v);
  const std::string stands = verdict ? fmt::format("complete (its passport says {})", v)
                                     : fmt::format("ended for good (its passport says {}: its run.log is missing lines; "
                                                   "no resume continues the run, one only finishes its ending)",
                                                   v);
  if (!sealed)  // a sealed one's final seal, checked before, vouches for the passport
    if (const std::string why = passport_unlike_its_run(dir, report::read_passport(dir), declared, a.profile_sha256);
        !why.empty())
      throw ConfigError(dir + "/passport.json: " + why + ": the passport was changed after its run wrote it; "
                        "nothing done (the folder is as it was)");
  const int rc = exit_code_of(outcome_named(v).value_or(RunOutcome::Error));
  const bool junit_staged = fs::is_regular_file(dir + "/junit.xml.tmp", ec);
  // The ending could not write report.html (a page there is another ending's).
  const bool report_listed = std::find(steps.begin(), steps.end(), kStepReport) != steps.end();
  const bool no_report = report_listed || !fs::exists(dir + "/report.html", ec);
  std::vector<std::string> left;
  if (junit_staged) left.emplace_back("junit.xml put in place");
  if (no_report) left.emplace_back(sealed ? "report.html written and sealed with the rest" : "report.html written");
  if (!a.no_history) left.emplace_back("the history row recorded");
  const std::string what = left.empty() ? std::string("nothing left") : fmt::format("{}", fmt::join(left, ", "));
  if (a.dry_run) {
    std::cout << fmt::format("rig run --dry-run: {} is {}; its ending stopped before it finished: a resume does what "
                             "is left ({}); nothing is measured or computed again.\n",
                             shown_text(dir), stands, what);
    if (!a.no_history && !a.history_left_behind.empty()) std::cout << "  warning: " << a.history_left_behind << "\n";
    return kExitPass;
  }
  const std::string unended = earlier_attempt_unended(dir);  // before this attempt's first line
  auto log = run_log_or_say(a, std::make_shared<LogLoss>(),
                            "its ending was not finished: nothing was done, the folder is as it was",
                            resume_key_words(a, sealed));
  log->info("rig {} run: out {}: the run is {}; finishing its ending ({})", RIG_VERSION, shown_text(dir), stands, what);
  say_where_the_account_broke_off(unended, *log);
  if (!a.no_history) say_history_left_behind(a, *log);  // another --db: the run's own database never gets this row
  // What this resume did and what is still owed, each said as it came out (a line integrator's
  // review: a history row the database refused was said "recorded").
  std::vector<std::string> did, owed;
  if (junit_staged) {
    fs::rename(dir + "/junit.xml.tmp", dir + "/junit.xml", ec);  // the ending that wrote the passport staged it
    if (ec) log->error("junit.xml not put in place: {}", ec.message()), owed.emplace_back("junit.xml put in place");
    else did.emplace_back("junit.xml put in place");
  }
  if (no_report) try {
      report::write_report(dir, true);  // the run's own page, before its final seal
      // A final seal made without the page (the ending could not write it) takes it in now: the
      // seal was checked before this resume trusted the folder.
      if (sealed) {
        std::vector<std::string> files = sealed_files(dir);
        if (std::find(files.begin(), files.end(), "report.html") == files.end()) files.emplace_back("report.html");
        seal_run_folder(dir, *key, files, std::nullopt, v);
        drop_previous_seal(dir);
        log->info("run folder sealed again with report.html (seal.json, key {})", key->id);
      }
      did.emplace_back(sealed ? "report.html written and sealed with the rest" : "report.html written");
    } catch (const std::exception& e) {
      log->error("report.html not written: {}", e.what());
      owed.emplace_back("report.html written");  // still left: the list stays
    }
  if (!a.no_history) {
    const nlohmann::json passport = report::read_passport(dir);
    if (record_in_history(a, hw, passport, passport.value("out_dir", dir), *log)) did.emplace_back("the history row recorded");
    else owed.emplace_back("the history row (the database did not take it)");
  } else if (std::find(steps.begin(), steps.end(), kStepHistory) != steps.end()) {
    // --no-history records nothing, but the row the run was meant to have is still owed: the
    // list keeps it for a later resume or `rig history --record` (a re-test: it was removed, the
    // run in no database and nothing saying so).
    if (owed.empty()) write_pending_steps(dir, {kStepHistory});
    log->warn("its history row is still to be recorded (--no-history): {} records it", a.record_command);
    owed.emplace_back("the history row (--no-history)");
  }
  const bool done = owed.empty();
  if (done) {
    // What a stop inside an earlier ending can leave beside a finished one goes with the list: a
    // half-written list (its staged copy) and the seal the final seal replaced (a re-test: a kill
    // between the final seal's rename and the old one's removal left seal.prev.json for good).
    fs::remove(pending, ec);
    fs::remove(pending + ".tmp", ec);
    if (sealed) drop_previous_seal(dir);
  }
  const std::string line =
      done ? fmt::format("{}: the run was {}; its ending is finished: {}", shown_text(dir), stands,
                         did.empty() ? std::string("nothing was left") : fmt::format("{}", fmt::join(did, ", ")))
           : fmt::format("{}: the run was {}; its ending is not finished yet: {}still to do: {} (a later rig run "
                         "--resume {} does it{})",
                         shown_text(dir), stands,
                         did.empty() ? std::string() : fmt::format("{} done; ", fmt::join(did, ", ")),
                         fmt::join(owed, ", "), shell_word(dir),
                         a.no_history ? ", without --no-history; or " + a.record_command : std::string());
  log->info("{} (exit {})", line, rc);
  std::cerr << line << "\n";
  return rc;
}

// Whether a phase after the first `completed` uses the devices (records, moves, steps the loop):
// a resume with none left (a run stopped at its ending, or in `loop-figures`; read_checkpoint
// puts a loop test the DUT did not run back among them, as the DUT is asked again, which uses the
// devices unless the link refuses it unasked: Phase::uses_devices) opens no device, asks no
// operator question and takes no table lock. A new run always has some.
bool devices_left(const std::vector<Phase>& phases, std::size_t completed) {
  return std::any_of(phases.begin() + static_cast<std::ptrdiff_t>(completed), phases.end(),
                     [](const Phase& ph) { return !ph.from_records && ph.uses_devices; });
}
// Why a resume opens no device, as its log and its dry run say it.
std::string no_device_needed(const std::string& plant, const std::vector<Phase>& phases, std::size_t completed) {
  const bool loop_left = std::any_of(phases.begin() + static_cast<std::ptrdiff_t>(completed), phases.end(),
                                        [](const Phase& ph) { return !ph.from_records; });
  return std::string("every phase left computes from the run's records") +
         (loop_left ? " or is the loop test the DUT's link refuses without asking it" : "") +
         ": nothing is powered or moved" + (plant == "hardware" ? ", and the DUT need not be mounted" : "");
}

// The interrupted ending a resume would record first (record_an_interrupted_ending) has no
// database to go to under --no-history, and this attempt's ending replaces its passport: it would
// be lost for good (a re-test: `--resume --no-history` removed the list, the ABORTED ending
// nowhere). Refused before anything is done; --record it first, or resume into a database.
void refuse_to_drop_an_interrupted_ending(const RunArgs& a) {
  if (!a.no_history) return;
  if (const std::string outcome = owed_interrupted_ending(a.out); !outcome.empty())
    throw ConfigError(fmt::format("{}: its {} ending is still to be recorded in the history ({} lists `history`), "
                                  "and --no-history would lose it once this attempt's ending replaces the passport: "
                                  "record it first ({}) or resume without --no-history",
                                  a.out, outcome, kEndingPending, a.record_command));
}

// An earlier attempt's ending that stopped the run (ABORTED, ERROR) and could not record its row
// (.ending-pending lists `history`) is recorded when its resume starts, before this attempt's
// own ending records the same row again: the row's `earlier` then names it (a line integrator's
// review: the ABORTED ending was lost from the history once the resume ended FAIL). A database
// still out of reach stops the resume (exit 2), the ending kept.
void record_an_interrupted_ending(const RunArgs& a, const toml::table& hw, spdlog::logger& log) {
  const std::string outcome = a.no_history ? std::string() : owed_interrupted_ending(a.out);
  if (outcome.empty()) return;
  const nlohmann::json passport = report::read_passport(a.out);
  // Not recorded now, it never would be: this attempt's ending replaces its passport (a re-test:
  // a PostgreSQL server down at the resume, the ABORTED ending lost). So the resume stops here,
  // the folder as it was but for run.log.
  if (!record_in_history(a, hw, passport, passport.value("out_dir", a.out), log, outcome))
    throw ConfigError(fmt::format("{}: its {} ending could not be recorded in the history (run.log says why), and this "
                                  "resume's ending would replace it: resume once the database can be reached, or "
                                  "record it first (rig history --record {} --db URL); nothing done",
                                  shown_text(a.out), outcome, shell_word(a.out)));
  std::vector<std::string> steps = pending_steps(a.out).value_or(std::vector<std::string>{});
  steps.erase(std::remove(steps.begin(), steps.end(), kStepHistory), steps.end());
  write_pending_steps(a.out, steps);
}

// The table timing the plan's moves are costed with: on hardware, the [table] section's client
// settle and poll and, where it sets them, the drive's velocity, acceleration and settle (else
// the drive keeps its own, which the plan takes as the emulated drive's power-on values); on the
// emulated plant, the profile's [plant.table] drive (its power-on velocity, acceleration and
// settle) with the client's defaults.
acceptance::TableTiming planned_table_timing(const RunArgs& a, const toml::table& hw, const toml::table& plant_cfg) {
  acceptance::TableTiming t;
  if (a.plant != "hardware") {
    const plant::TableParams d = plant::table_params_from_toml(cfg::get_table(plant_cfg, "table"));
    t.velocity_dps = d.velocity_dps;
    t.accel_dps2 = d.accel_dps2;
    t.drive_settle_s = d.settle_s;
    return t;
  }
  const toml::table* table = cfg::get_table(hw, "table");
  if (!table) return t;
  const modbus::TableOptions o = modbus::table_options_from_toml(*table);
  t.settle_s = o.settle_s;
  t.poll_s = o.poll_s;
  t.velocity_dps = o.velocity_dps.value_or(t.velocity_dps);
  t.accel_dps2 = o.accel_dps2.value_or(t.accel_dps2);
  t.drive_settle_s = o.drive_settle_s.value_or(t.drive_settle_s);
  // A CiA 402 drive is sent whole units: the plan moves at what the drive is sent (0.1 deg/s
  // sent as 0.12 was planned at 0.1, a review). Zero is refused by the map's check before this.
  if (modbus::table_drive(*table) == "cia402") {
    const modbus::DriveMap map = modbus::table_drive_map(*table);
    if (o.velocity_dps && map.has(modbus::Obj::kProfileVelocity))
      if (const double u = std::llround(map.dps_to_velocity_units(*o.velocity_dps)); u != 0)
        t.velocity_dps = std::fabs(map.velocity_units_to_dps(u));
    if (o.accel_dps2 && map.has(modbus::Obj::kProfileAcceleration))
      if (const double u = std::llround(map.dps2_to_accel_units(*o.accel_dps2)); u != 0)
        t.accel_dps2 = std::fabs(map.accel_units_to_dps2(u));
  }
  return t;
}

// The dry run's account of the hardware it would drive, read from the hardware file as the run
// reads it (nothing opened): which drive and map, the speeds the moves are sent at, the DUT's
// link and stream layout, the GPIO lines (it named only the file: an integrator's review).
std::vector<std::string> hardware_plan(const toml::table& hw, const acceptance::TableTiming& timing,
                                       const DutLinkOptions& dut) {
  std::vector<std::string> out;
  if (const toml::table* t = cfg::get_table(hw, "table")) {
    const std::string where = t->contains("modbus") ? "Modbus " + cfg::get_string(*t, "modbus")
                                                    : "Modbus RTU " + cfg::get_string(*t, "rtu");
    const long long unit = t->contains("unit") ? cfg::get_int(*t, "unit", {}, 0, 247) : 1;
    const std::string drive = modbus::table_drive(*t) == "cia402"
                                  ? [&] {
                                      const modbus::DriveMap m = modbus::table_drive_map(*t);
                                      return "a CiA 402 drive, drive map " + m.path + " (\"" + m.name + "\")";
                                    }()
                                  : std::string("a rig-v1 table (docs/table-registers.md)");
    // Speeds the hardware file does not give are not sent: the drive keeps its own, and the plan
    // assumes the defaults (a code review: "(as sent)" where nothing is sent).
    // Each value said for itself: one given and one not read "(as sent)" for both (a re-test).
    const bool v_sent = t->contains("velocity_dps"), a_sent = t->contains("accel_dps2");
    const auto said = [](bool sent, const char* key) {
      return sent ? std::string("as sent") : fmt::format("planned: no {}, none sent; the drive's own", key);
    };
    const std::string speeds =
        v_sent == a_sent
            ? fmt::format("{:g}°/s, {:g}°/s² ({})", timing.velocity_dps, timing.accel_dps2,
                          v_sent ? "as sent"
                                 : "planned: no [table] velocity_dps or accel_dps2, so none is sent; the drive moves "
                                   "at its own")
            : fmt::format("{:g}°/s ({}), {:g}°/s² ({})", timing.velocity_dps, said(v_sent, "velocity_dps"),
                          timing.accel_dps2, said(a_sent, "accel_dps2"));
    out.push_back(fmt::format("Table: {} on {}, unit {}; moves at {}", drive, where, unit, speeds));
    // What the dry run could not check (a review: it said nothing of it): a rig-v1 drive's travel
    // is in its own registers, read when it answers.
    if (modbus::table_drive(*t) != "cia402")
      out.push_back("Travel: the rig-v1 drive's own LIMIT registers, not readable here; the run checks U10/U20 "
                    "against them after homing, before the first recording (exit 2 if outside)");
  }
  if (const toml::table* d = cfg::get_table(hw, "dut")) {
    std::string stream = "the rig protocol (docs/can-protocol.md), 1000 Hz";
    if (dut.stream) {
      const link::DbcStreamSpec& sp = dut.stream->spec();
      stream = fmt::format("{} of {}: counter {} ({} bits), x {}, y {}, {} sample(s) per frame, {:g} Hz",
                           "[dut.stream]", cfg::get_string(*d, "dbc"), sp.counter, dut.stream->counter_bits(), sp.x,
                           sp.y.empty() ? std::string("none") : sp.y, sp.samples_per_frame, sp.rate_hz);
    }
    out.push_back(fmt::format("DUT: CAN {}; stream {}; commands {}, loop test {}", cfg::get_string(*d, "can"), stream,
                              dut.can.commands ? "yes" : "no ([dut] commands = false: the serial is --serial's)",
                              dut.can.runs_loop_test() ? "yes" : "not run"));
  }
  if (const toml::table* g = cfg::get_table(hw, "gpio"))
    out.push_back(fmt::format("GPIO: {}: DUT power {}, e-stop {}", cfg::get_string(*g, "chip"), cfg::get_string(*g, "power"),
                              cfg::get_string(*g, "estop")));
  return out;
}

// The serial the run's DUT reported (checkpoint.json's state.dut.serial), empty when no DUT has
// reported one or the checkpoint cannot be read (its own check, later, names what is wrong).
std::string reported_serial(const std::string& run_dir) {
  try {
    const nlohmann::json j = parse_json_unique_keys(file_text(run_dir + "/checkpoint.json"));
    const nlohmann::json& s = j.at("state").at("dut").at("serial");
    return s.is_string() ? s.get<std::string>() : std::string();
  } catch (const std::exception&) {
    return {};
  }
}

// A run writes its checkpoint once its first phase completes, so a folder without one holds at
// most the record that phase was writing. More records without it (a checkpoint removed or lost)
// were re-measured from bring-up, each set aside as *.interrupted-N, and the dry run said the run
// had stopped before its first phase (an outside review: 13 completed captures, two hours of
// `paper` again). The folder cannot say which phases completed: refused, the records left as
// they are.
void refuse_records_without_checkpoint(const std::string& dir) {
  if (path_kind(Executive::checkpoint_path(dir), "checkpoint") != PathKind::missing) return;
  std::vector<std::string> records;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir + "/captures", ec))
    if (e.path().extension() == ".cap") records.push_back("captures/" + e.path().filename().string());
  if (fs::exists(dir + "/" + acceptance::kLoopTestFile)) records.emplace_back(acceptance::kLoopTestFile);
  if (records.size() <= 1) return;
  std::sort(records.begin(), records.end());
  std::string listed;
  for (std::size_t i = 0; i < records.size() && i < 3; ++i) listed += (i ? ", " : "") + shown_text(records[i]);
  if (records.size() > 3) listed += ", ...";
  throw ConfigError(fmt::format("{}: missing, but the folder holds {} records ({}): a run writes its checkpoint once "
                                "its first phase completes, so it was removed or lost, and the folder cannot say which "
                                "phases completed (damaged run folder; start a new run: the records stay as they are)",
                                Executive::checkpoint_path(dir), records.size(), listed));
}

// After a stop, what is kept and how to go on, where the technician looks: stderr and run.log.
// `key_words`: what the resume's line needs to name the station's key (resume_key_words).
void say_how_to_continue(const std::string& out, std::size_t kept, std::size_t phases, const std::string& why,
                         const std::string& key_words, spdlog::logger& log) {
  const std::string hint = fmt::format(
      "to continue: rig run --resume {}{} ({} of {} phases complete{}; `rig run --dry-run --resume {}{}` shows what a "
      "resume repeats)",
      shell_word(out), key_words, kept, phases, why, shell_word(out), key_words);
  std::cerr << hint << "\n";
  log.info("{}", hint);
}

// run.json of the run folder `dir`, read as a resume reads it: a key twice refused, its fields
// into `a` (read_invocation), and the folder's profile.toml told where its relative paths resolve
// ([plant.firmware] dbc: where the profile was, run.json's profile_folder; a run started before
// it kept one: beside the copy).
nlohmann::json read_run_json(const std::string& dir, RunArgs& a) {
  const std::string inv_path = dir + "/run.json";
  nlohmann::json inv;
  try {
    inv = parse_json_unique_keys(file_text(inv_path));
  } catch (const std::exception& e) {
    throw ConfigError(inv_path + ": unreadable: " + e.what());
  }
  read_invocation(inv_path, inv, a);
  if (const std::string folder = inv.value("profile_folder", std::string()); !folder.empty())
    cfg::set_relative_folder(dir + "/profile.toml", folder);
  return inv;
}

// The folder's profile.toml (read as `q`) against what run.json says the run started with: its
// name and its digest. The checkpoint ties a resume to the profile it started with; a run stopped
// before its first checkpoint had only run.json, which did not (an automation review: limits
// loosened in the folder's profile.toml, then resumed: PASS). Since 2026-12-02 run.json holds the
// digest too. Without the digest (run.json from a rig before it wrote one, or the field deleted)
// only a checkpoint ties the resume to its profile: none, and the resume is refused (a re-test:
// the field deleted, an edited profile ran under the built-in's name, PASS).
void check_the_folders_profile(const std::string& dir, const nlohmann::json& inv, const acceptance::Profile& q) {
  const std::string copy = dir + "/profile.toml";
  if (inv.contains("profile") && inv["profile"] != q.name)
    throw ConfigError(
        fmt::format("{}/run.json: field 'profile': {}, but {} is profile \"{}\"", dir, inv["profile"].dump(), copy, q.name));
  if (!inv.contains("profile_digest") && path_kind(dir + "/checkpoint.json", "--resume") == PathKind::missing)
    throw ConfigError(fmt::format("{}/run.json: no field 'profile_digest', and no checkpoint: nothing ties {} to the "
                                  "profile the run started with; start a new run",
                                  dir, copy));
  if (inv.contains("profile_digest") && inv["profile_digest"] != q.digest)
    // Its own digest not printed: it made an edited profile's resume pass in an unsealed folder (a review).
    throw ConfigError(fmt::format("{}/run.json: field 'profile_digest': {}, not the digest of {} (which a resume "
                                  "reads): not the profile the run started with (edited since?); start a new run",
                                  dir, inv["profile_digest"].dump(), copy));
}

// What a run's checkpoint is tied to: its profile, plant and DUT.
nlohmann::json run_identity(const acceptance::Profile& p, const RunArgs& a) {
  return {{"profile_digest", p.digest}, {"plant", a.plant}, {"serial", a.serial}};
}

// Why a resume of `dir` would be refused now, as the resume itself reads the folder (nothing
// opened; its own checks before the devices, in its order, on what the folder holds): run.json
// gone (the folder removed or moved while the run went on), records without a checkpoint,
// run.json's fields, the profile's copy against run.json, its [plant], the checkpoint and the
// records it names. "" when it would start. An ABORTED or ERROR ending said "to continue: rig run
// --resume DIR" and that resume was exit 2 (an integrator's review, and a re-test of the first
// version, which checked only run.json and the checkpoint).
std::string resume_refusal(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_regular_file(dir + "/run.json", ec))
    return "its run.json is gone from " + shown_text(dir) +
           " (the folder removed or moved while the run went on): a folder moved whole resumes where it is now "
           "(rig run --resume NEW-PLACE); else start a new run";
  try {
    refuse_a_log_missing_lines(dir);
    refuse_records_without_checkpoint(dir);
    RunArgs again;
    again.db = "(the resume's own)";  // a masked --db is given again, not a refusal
    const nlohmann::json inv = read_run_json(dir, again);
    std::string source;
    const toml::table t = acceptance::load_profile_table(dir + "/profile.toml", source);
    const acceptance::Profile q = acceptance::parse_profile(t, source);
    check_the_folders_profile(dir, inv, q);
    (void)plant::validate_plant_section(plant::plant_section(t));
    acceptance::ProcedureState state(q);
    const std::vector<Phase> phases = acceptance::build_phases(q, state);
    MeasurementSet values;
    acceptance::declare_values(q, phases, values);
    spdlog::logger quiet("resume-check");  // no sinks
    (void)Executive::read_checkpoint(dir, phases, values, state, run_identity(q, again), quiet, true);
  } catch (const ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return dir + ": " + e.what();
  }
  return "";
}

// "no resume: why; start a new run" on stderr and in run.log.
void say_no_resume(const std::string& why, spdlog::logger& log) {
  // "another --out": a new run into this folder is refused, its run kept as it ended.
  const std::string no =
      "no resume: " + why + (why.find("start a new run") == std::string::npos ? "; start a new run (another --out)" : "");
  std::cerr << no << "\n";
  log.info("{}", no);
}

// An ending with no resume whose own files a full disk kept out (.ending-pending: report.html,
// junit.xml, the history row) is finished by `rig run --resume` (finish_pending_ending): said after
// "no resume", which alone sent the technician away from the steps left (a code review). Not where
// the final seal is among them (a_resume_finishes): a sealed run finishes only under its final seal.
void say_how_to_finish(const std::string& out, const std::string& key_words, spdlog::logger& log) {
  const std::vector<std::string> steps = pending_steps(out).value_or(std::vector<std::string>{});
  if (steps.empty() || final_outcome_of(out).empty() || !a_resume_finishes(out, steps)) return;
  const std::string line = fmt::format("its ending is not finished ({} lists: {}): rig run --resume {}{} finishes it "
                                       "once the cause is mended (nothing is measured or computed again)",
                                       kEndingPending, fmt::join(steps, ", "), shell_word(out), key_words);
  std::cerr << line << "\n";
  log.info("{}", line);
}

// After an ABORTED or ERROR ending: how to go on (say_how_to_continue), or, where the folder would
// refuse its resume now (resume_refusal), "no resume: why; start a new run".
// `refused`: resume_refusal(out) where the caller has it already (it reads the checkpoint and
// every capture it names).
void offer_a_resume(const std::string& out, std::size_t checkpointed, std::size_t phases, const std::string& why,
                    const std::string& key_words, spdlog::logger& log,
                    const std::optional<std::string>& refused_already = std::nullopt) {
  if (const std::string refused = refused_already ? *refused_already : resume_refusal(out); !refused.empty()) {
    say_no_resume(refused, log);
    return;
  }
  // Kept: the phases the checkpoint holds, as `--dry-run --resume` counts them (a review: a
  // resume stopped before computing its kept records again said 13 of 19, its dry run 15).
  std::error_code ec;
  say_how_to_continue(out, fs::exists(Executive::checkpoint_path(out), ec) ? checkpointed : 0, phases, why, key_words,
                      log);
}

int do_run_watched(RunArgs a, CancelSource& cancel);

int do_run(RunArgs a) {
  // A reader that went away (a dead tee, `| head -1`) must not end a run between a move and the
  // safe state: writes to it fail with EPIPE instead, and the run's files carry what it did.
  // (Only here: `rig dut stream | head` should still end when its reader does.)
  ::signal(SIGPIPE, SIG_IGN);
  CancelSource cancel;
  SignalWatcher signals(cancel);  // before any backend thread exists
  // This attempt's last line in its run.log, however it ends (returned, or thrown to main), once
  // its loggers are gone; a line the disk refuses is left out, and the next resume says so.
  struct AttemptEnd {
    ~AttemptEnd() {
      if (g_attempt_log.empty()) return;  // refused before any run.log was opened
      std::ofstream out(g_attempt_log, std::ios::app);
      out << utc_now_ms() << " info  " << kAttemptEnds << "\n" << std::flush;
      if (!out)  // said, as any line the disk refuses is (make_logger); the next resume marks it
        std::cerr << "rig: warning: " << g_attempt_log << ": its closing line could not be written\n";
    }
  } attempt_end;
  return do_run_watched(std::move(a), cancel);
}

// The passport's exit code, kept for main's handler: set while the watcher still holds the
// signals, so one that comes once it is gone (the closing table still in stdout's buffer, written
// at exit) ends the process with it, not the abort's 3 (a review: PASS in passport.json and
// junit.xml, exit 3). Only where a passport stands (not a dry run, not a refusal).
int the_passports_exit(int rc) {
  cli::g_verdict_exit.store(rc);
  return rc;
}

// `rig run --dry-run`: the run's plan as the run would make it, every check the run makes before
// a device opens, and nothing written or opened. Its exit code: 2 where the history is locked.
int print_dry_run(const RunArgs& a, const toml::table& hw, const toml::table& plant_cfg, const acceptance::Profile& p,
                  const DutLinkOptions& dut, const std::vector<Phase>& phases, MeasurementSet& values,
                  acceptance::ProcedureState& state, const nlohmann::json& identity, bool sealed,
                  const std::string& unjudged, bool history_locked) {
  // A table another rig process commands now is said, as the run would say it, first (a review):
  // a resume's only where a phase left uses the devices (below).
  auto check_the_table = [&] {
    if (a.plant == "hardware") TableLock::check_free(modbus::table_identity(*cfg::get_table(hw, "table", true)));
  };
  if (a.resume.empty()) check_the_table();
  // Without --out the run makes its own new folder under runs/, which holds no earlier run.
  // A live run's folder says so first, as the run itself would.
  if (a.resume.empty() && !a.out.empty()) FolderLock::check_free(a.out, "--out " + a.out);
  const bool taken_over = check_run_folder(a.out.empty() ? "runs" : a.out, a.resume.empty() && !a.out.empty(),
                                           a.resume.empty() ? "--out" : "--resume", p.source);
  // The run's own new folder under runs/ is empty; only its place is checked.
  if (a.resume.empty())
    refuse_a_folder_a_new_run_cannot_own(a.out.empty() ? "runs" : a.out, "--out", sealed && !a.out.empty(), taken_over);
  // A run.log the run could not open: a stopped start's it would take over (a resume's below, after
  // the refusals that say the folder has no resume at all).
  if (a.resume.empty() && !a.out.empty()) refuse_a_run_log_it_cannot_write(a.out);
  const std::string room = check_room(a.resume.empty() ? (a.out.empty() ? "runs" : a.out) : a.resume,
                                      a.resume.empty() ? "--out" : "--resume", p, !a.resume.empty());
  // A resume's checkpoint is checked as the run would check it (its captures read, nothing
  // opened), before the plan is printed, so the plan says what the resume keeps, computes
  // again and still records.
  std::vector<std::string> completed;
  if (!a.resume.empty()) {
    spdlog::logger quiet("dry-run");  // no sinks: a dry run writes nothing
    if (!sealed) refuse_a_final_verdict(a.resume);  // a sealed folder's verdict is its seal's (checked above)
    refuse_a_log_missing_lines(a.resume);
    refuse_a_run_log_it_cannot_write(a.resume);
    completed = Executive::read_checkpoint(a.resume, phases, values, state, identity, quiet, true).completed;
  }
  const bool devices_needed = devices_left(phases, completed.size());
  if (!a.resume.empty() && devices_needed) check_the_table();
  TerminalView plan_view(stdout);
  std::cout << fmt::format("rig run --dry-run: profile '{}' ({}) on {}; nothing is touched.\n", p.name,
                           shown_text(p.source),
                           a.plant == "hardware" ? "the hardware of " + shown_text(a.hardware)
                                                 : std::string("the emulated plant (a simulated DUT, table and GPIO)"));
  // The angles the run turns to, and whose they are: a mount's calibration that never reached
  // them was found only at the prompt, or not at all with --yes (a technician's review).
  const toml::table* pr = a.plant == "hardware" ? cfg::get_table(hw, "procedure") : nullptr;
  if (!unjudged.empty()) std::cout << "Note: " << unjudged << "\n";
  if (taken_over) std::cout << "Note: " << taken_over_note(a.out) << "\n";
  for (const std::string& n : faults_past_the_plan(parse_injections(a.inject), planned_device_s(phases)))
    std::cout << "Note: " << n << "\n";
  std::cout << fmt::format("Orientations: U10 at {:g}°, U20 at {:g}° ({})\n", p.u10_deg, p.u20_deg,
                           pr && pr->contains("u10_deg") ? "[procedure] of " + shown_text(a.hardware)
                                                         : std::string("the profile's"));
  if (!devices_needed)
    std::cout << "Devices: none opened: " << no_device_needed(a.plant, phases, completed.size()) << "\n";
  else if (a.plant == "hardware")
    for (const std::string& line : hardware_plan(hw, planned_table_timing(a, hw, plant_cfg), dut))
      std::cout << line << "\n";
  plan_view.plan(phases, completed.size());
  if (devices_needed)  // bring-up's own steps among them: none happens without devices
    for (const std::string& s : planned_skips(a, hw, dut.can, p)) std::cout << "  skipped: " << s << "\n";
  if (!a.resume.empty()) {
    std::string kept, again;  // completed is a prefix of phases (read_checkpoint checks it)
    for (std::size_t i = 0; i < completed.size(); ++i) {
      std::string& list = phases[i].from_records ? again : kept;
      list += (list.empty() ? "" : ", ") + completed[i];
    }
    if (fs::exists(Executive::checkpoint_path(a.resume)))
      std::cout << fmt::format("Resume: {} checked with the records it names (captures, loop-test.csv){}; {} of {} "
                               "phases complete.\n",
                               Executive::checkpoint_path(a.resume), sealed ? " and the station's seal" : "",
                               completed.size(), phases.size());
    else  // stopped before its first checkpoint (or the file is gone): nothing of it is trusted
      std::cout << fmt::format("Resume: {} has no checkpoint (the run stopped before its first phase completed){}; "
                               "0 of {} phases complete: every phase runs again from bring-up.\n",
                               a.resume, sealed ? "; the station's seal checked" : "", phases.size());
    if (!kept.empty()) std::cout << "  kept (not recorded again): " << kept << "\n";
    if (!again.empty()) std::cout << "  computed again from the kept records: " << again << "\n";
    std::string left;
    for (std::size_t i = completed.size(); i < phases.size(); ++i) left += (left.empty() ? "" : ", ") + phases[i].id;
    std::cout << "  still to run: "
              << (left.empty() ? "nothing (every phase is recorded; the verdict is what is left)" : left) << "\n";
    // The losses the resume plays again, named where the `to continue` hint sends the technician
    // (a review: that hint said they repeat, the dry run did not).
    const std::string drops = fmt::format("{}", fmt::join(sample_losses(a.inject), ", "));
    if (!drops.empty() && devices_needed)  // with no device opened nothing is replayed (a review)
      std::cout << "  repeated from run.json's faults: " << drops << " (samples the emulated DUT lost are part of its "
                << "history: a loss that ended the run in ERROR ends the resume so again)\n";
    // Named, not only the rule (a technician's review): which file the resume sets aside.
    for (const std::string& f : partial_records(a.resume, state.slot()))
      std::cout << "  left partial by the interruption: " << f << " (kept as " << f
                << ".interrupted-N when its phase records again)\n";
  }
  // Where the run will be recorded: a typo in --db or [history] url would create a database
  // (and its folders) that the station's history never reads (a technician's review).
  if (a.no_history) {
    std::cout << "History: not recorded (--no-history)\n";
  } else {
    const std::string url = history_url(a, hw);
    std::string fresh;
    if (const std::optional<history::SqliteFile> file = history::sqlite_file(url); file && !file->exists)
      fresh = file->missing_folder.empty()
                  ? " (not there yet: the run creates it)"
                  : " (not there yet: the run creates it and the folder " + file->missing_folder +
                        ", the built-in default's)";
    std::cout << "History: " << history::mask_password(url) << fresh
              << (history_locked ? " (locked by another process now: said above)" : "") << "\n";
  }
  // What a resume leaves in the run's own database, said before it runs as the resume will say it.
  if (!a.history_left_behind.empty()) std::cout << "  warning: " << a.history_left_behind << "\n";
  if (!room.empty()) std::cout << room << "\n";
  double total = 0;
  for (std::size_t i = completed.size(); i < phases.size(); ++i) total += phases[i].planned_s;
  if (!devices_needed)
    std::cout << "Estimated duration of what is left: no device time: the phases left only compute (seconds of wall "
                 "time)\n";
  else
    std::cout << fmt::format("Estimated duration{}: {} of device time{}, plus bring-up (the DUT's power-up and the "
                             "table's homing, which depends on where the table stands) and any retries\n",
                             completed.empty() ? "" : " of what is left", TerminalView::hms(total),
                             a.plant == "emulated" ? " (emulated: seconds of wall time)" : ", the same in wall time");
  return history_locked ? kExitUsage : kExitPass;
}

// A new run's run.json: what its resume needs to go on as the run started (read_invocation).
nlohmann::json new_run_invocation(const RunArgs& a, const toml::table& hw, const acceptance::Profile& p) {
  nlohmann::json invocation = {
      {"plant", a.plant},         {"hardware", a.hardware.empty() ? "" : fs::absolute(a.hardware).string()},
      {"serial", a.serial},       {"profile", p.name},
      {"profile_source", p.source}, {"profile_digest", p.digest},
      {"software", std::string("rig ") + RIG_VERSION}, {"started", iso8601_utc_now()},
      {"station", station_of(a, hw)}};
  // Where the profile's relative paths resolve, for its resume (it reads the folder's copy).
  if (p.source.rfind("builtin:", 0) != 0) {
    std::error_code ec;
    // (lexically normal, and without the trailing '/' "./x.toml" left)
    const fs::path folder = fs::absolute(p.source, ec).lexically_normal().parent_path();
    if (!ec) invocation["profile_folder"] = folder.string();
  }
  // Where the run is recorded, for its resume: --no-history, or a --db URL (masked when it
  // carries a password, which run.json never holds; the resume must then give it again).
  if (a.no_history) {
    invocation["no_history"] = true;
  } else if (!a.db.empty()) {  // an SQLite file made absolute: a resume may start elsewhere
    invocation["db"] = history::kept_form(a.db);
  } else {  // as it resolved now: the resume records there too (read_invocation)
    invocation["history_db"] = history::kept_form(history_url(a, hw));
  }
  // Repeated by a resume (read_invocation).
  if (const std::vector<std::string> drops = sample_losses(a.inject); !drops.empty()) invocation["faults"] = drops;
  return invocation;
}

// After the phases: a verdict (PASS, FAIL) whose records are gone, changed or short of log lines
// becomes ERROR with its reason in res; a stopped run (ABORTED, ERROR) whose log lost lines has
// that loss added to its reason. Returns why the run has no resume ("" while it has one).
std::string judge_the_records(const std::string& out, RunResult& res, acceptance::ProcedureState& state,
                              const std::optional<seal::Key>& key, const LogLoss& loss, spdlog::logger& log) {
  // A verdict stands on its records: one whose captures or log were removed meanwhile is an
  // ERROR (exit 4) naming them, never a PASS nobody can check.
  // Why the run has no resume, said after its ending ("" while it has one): a resume would refuse
  // the folder (exit 2). Kept as said, not read back out of the reason's text (a review: a record
  // changed mid-run was named as lines missing from run.log).
  const std::string records_changed_why = "the run's records in " + shown_text(out) + " changed after they were written";
  std::string no_resume_why = res.records_changed ? records_changed_why : "";
  // A stopped run whose log lost lines has no resume either: its ending would give a verdict beside
  // the hole (a review). Lines refused after this point (the closing lines) leave the verdict as it
  // stands, as a signal after the passport does.
  if ((res.outcome == RunOutcome::Aborted || res.outcome == RunOutcome::Error) && !res.config_error)
    if (const std::string log_missing = loss.said(); !log_missing.empty()) {
      res.message += "; " + log_missing;
      if (no_resume_why.empty()) no_resume_why = log_missing_lines_why(out);
      log.error("{}", log_missing);
    }
  if (res.outcome == RunOutcome::Pass || res.outcome == RunOutcome::Fail) {
    const std::vector<std::string> gone = records_gone(out, state.slot());
    std::vector<std::string> touched;
    const std::vector<std::string> changed = records_changed(out, state, key, touched);
    if (!touched.empty())
      log.warn("the run's records in {} were touched after they were written ({}), but hold what was recorded: "
               "the verdict stands on them",
               out, fmt::join(touched, ", "));
    const std::string log_missing = loss.said();
    no_resume_why = !gone.empty()      ? "the run's records are gone from " + shown_text(out)
                    : !changed.empty()   ? records_changed_why
                    : !log_missing.empty() ? log_missing_lines_why(out)
                                           : "";
    std::vector<std::string> why;
    if (!gone.empty())
      why.push_back(fmt::format("the run's records are gone from {} (removed while it ran): {}", out, fmt::join(gone, ", ")));
    if (!changed.empty())
      why.push_back(fmt::format("the run's records in {} changed after they were written: {}", out, fmt::join(changed, ", ")));
    if (!log_missing.empty()) why.push_back(log_missing);
    if (!no_resume_why.empty()) {
      res.outcome = RunOutcome::Error;
      res.message = fmt::format("{}; no verdict {}", fmt::join(why, "; "),
                                gone.empty() && changed.empty() ? "beside a hole in the run's account"
                                                                : "without the records as measured");
      log.error("{}", res.message);
    }
  }
  return no_resume_why;
}

// An ending the run folder refused (write_run_outputs threw `e`: a full disk, a folder made
// read-only or removed): said in run.log, recorded as ERROR where it still fits (the folder, the
// history), the lamps and stdout's OUTCOME line for the ending that stands, and whether and how
// the run goes on. The caller rethrows `e` (main's exit 4). earlier_*: the folder's passport.json
// and analysis.json as they were before this ending (an ABORTED ending's, resumed).
void end_short_of_files(const std::exception& e, const RunArgs& a, const toml::table& hw, const PassportInfo& info,
                        const RunResult& res, const MeasurementSet& values, Executive& exec,
                        const std::optional<FileStamp>& earlier_passport,
                        const std::optional<FileStamp>& earlier_analysis, RigIo& io, const std::string& no_resume_why,
                        const LogLoss& loss, const std::string& resume_key, spdlog::logger& log) {
  // An ERROR ending is that ending still, short of files: said so, not as an outcome that "could
  // not be" written beside the ERROR that was (a review read the two as contradicting).
  const bool was_error = res.outcome == RunOutcome::Error;
  if (was_error)
    log.error("the ERROR ending not written in full: {} (exit 4: the run folder cannot hold the run's records)", e.what());
  else
    log.error("outcome {} not written: {} (exit 4: the run folder cannot hold the run's records)",
               to_string(res.outcome), e.what());
  // Lines lost since the checkpoint last said so (the ending's own, these two): recorded there
  // too, where the disk takes it, so the resume offered below is refused (a review: lost late in
  // the ending, beside a refused passport, the resume ended PASS).
  if (!res.config_error) exec.record_the_log_loss();
  // An ERROR ending saying which outcome could not be written, never that outcome: in the
  // history (it promises every run; a folder deleted mid-run left no row, a review), and in the
  // folder where its passport and JUnit report still fit (a full disk refused the 600 kB
  // analysis.json and then nothing was written, though 300 kB were free: a CI job read "no test
  // reports", a review). A resume, once the folder can take the files, writes the ending again.
  RunResult unwritten = res;
  unwritten.outcome = RunOutcome::Error;
  // A stopped run's reason goes with it (SIGINT received; run.log is missing lines: ...): without
  // it an ABORTED run whose log lost lines read as resumable, and its resume ended PASS beside the
  // hole (a code review).
  unwritten.message =
      was_error ? fmt::format("{}; its ending not written in full to the run folder: {}", res.message, e.what())
                : fmt::format("outcome {} not written to the run folder: {}{}", to_string(res.outcome), e.what(),
                              res.outcome == RunOutcome::Aborted && !res.message.empty() ? "; " + res.message : "");
  const nlohmann::ordered_json error_passport = make_passport(info, unwritten, values);
  // Replaced too where it is an earlier ending's (a review: an ABORTED passport, resumed, stayed
  // beside a history row saying ERROR); kept where it is this ending's own, put in place before
  // what failed. Neither page nor an earlier analysis.json may stand beside the ERROR: the page
  // is drawn from a passport that is not (or no longer) the folder's, and both come again with
  // the resume's ending.
  const auto earlier = [](const std::optional<FileStamp>& then, const std::string& path) {
    const std::optional<FileStamp> now = stamp_of(path);
    return !now || (then && now->inode == then->inode && now->device == then->device);
  };
  std::error_code ec;
  fs::remove(a.out + "/report.html", ec);
  if (earlier_analysis && earlier(earlier_analysis, a.out + "/analysis.json")) fs::remove(a.out + "/analysis.json", ec);
  bool error_passport_written = false;
  if (earlier(earlier_passport, a.out + "/passport.json")) try {
      write_file_staged(a.out + "/junit.xml", junit_xml(info, unwritten, values));
      write_file_staged(a.out + "/passport.json", passport_text(error_passport));
      commit_staged(a.out + "/passport.json");
      commit_staged(a.out + "/junit.xml");
      error_passport_written = true;
      if (was_error) log.error("passport.json and junit.xml written with outcome ERROR (its ending not written in full)");
      else log.error("passport.json and junit.xml written with outcome ERROR (the outcome {} could not be)",
                      to_string(res.outcome));
    } catch (const std::exception& also) {
      for (const char* f : {"/junit.xml.tmp", "/passport.json.tmp"}) fs::remove(a.out + f, ec);
      log.error("nor an ERROR passport: {}", also.what());
    }
  if (!a.no_history) record_in_history(a, hw, error_passport, a.out, log);
  io.set_lamp(Lamp::Running, false);
  io.set_lamp(Lamp::Fail, true);  // no passport, no pass
  // The closing table and OUTCOME line of the ending that stands, as every other ending prints
  // them (a review: an empty stdout beside the ERROR passport a full disk left).
  // Only where that passport is in place: a table for a passport the folder does not hold misled
  // (a re-test: "OUTCOME: ERROR" beside an ABORTED passport.json).
  if (error_passport_written) {
    say_the_passport(error_passport, info.out_dir);
  } else if (std::error_code pe; !fs::exists(a.out + "/passport.json", pe)) {
    // No passport at all (the folder gone, or a full disk before any ending): the outcome line
    // still, which a station reads from stdout (a line integrator's review: stdout was empty),
    // and no table for a passport nobody can read. Beside an earlier ending's passport nothing.
    std::cout << "passport.json not written: the run folder could not take it (stderr says why)\n"
              << "OUTCOME: ERROR\n"
              << (a.plant == "emulated" ? kEmulatedPlantLine : "")
              << std::flush;
  }
  // What is kept goes on once the folder can take the files (a review: a full disk ended with
  // only "write failed", though the folder resumed to the same passport).
  // "No resume" only where the folder says so to the resume (the passport or the checkpoint took
  // the reason): where the disk refused both, the resume goes on, and saying otherwise sent the
  // technician away from a folder that then resumed to PASS (a review).
  const std::optional<std::string> refused =
      no_resume_why.empty() ? std::nullopt : std::optional<std::string>(resume_refusal(a.out));
  if (refused && !refused->empty()) {  // as the ending in full says it
    say_no_resume(no_resume_why, log);
    say_how_to_finish(a.out, resume_key, log);
  } else if (!res.config_error) {
    if (!no_resume_why.empty()) {  // on stderr with --quiet too, as `no resume:` is
      const std::string lost = loss.said();
      const std::string line = no_resume_why +
                               "; with the passport refused, nothing the disk took keeps a resume from going on" +
                               (lost.empty() ? std::string() : ": run.log stays short of the lines refused (" + lost + ")");
      std::cerr << line << "\n";
      log.info("{}", line);
    }
    offer_a_resume(a.out, res.checkpointed, res.phases.size(), "; once the folder can take the run's files",
                   resume_key, log, refused);
  }
}

// The emulation's own speed, as measured on this run (the replay that rebuilt the plant for a
// resume named apart: nothing of it was measured). wall_s: the run's wall time from after the
// operator's answers.
void say_the_plants_speed(plant::EmulatedPlant& w, double wall_s, double replayed_s, std::uint64_t replayed_samples,
                          spdlog::logger& log) {
  const double device = w.clock().now_s();
  const auto samples = w.samples_generated();
  const std::string replay =
      replayed_samples ? fmt::format(" ({:.1f} min and {} samples of them replayed the kept recordings)",
                                     replayed_s / 60, replayed_samples)
                       : std::string();
  const std::string line = fmt::format(
      "emulated plant: {:.1f} min of device time, {} DUT samples{}, in {:.2f} s wall: {:.0f}x real time, {:.2f} M "
      "samples/s",
      device / 60, samples, replay, wall_s, device / wall_s, static_cast<double>(samples) / wall_s / 1e6);
  std::cout << line << "\n";
  log.info("{}", line);
}

// The history the run records into, checked before anything opens: one this rig cannot open or
// write is said now, not after the DUT was measured. Returns true where a dry run found it locked.
// A dry run's history held locked by another process now: said, and the dry run goes on to its
// plan (a technician's re-test: a resume's dry run waited 10 s and printed only the lock); it
// exits 2 as the run would, whatever else it finds (a code review: a later error replaced the
// lock, and a resume's unfinished ending exited 0).
bool check_the_history(const RunArgs& a, const toml::table& hw, CancelSource& cancel) {
  if (a.no_history) return false;
  const std::string url = history_url(a, hw);
  try {
    check_history_can_record(url, !a.resume.empty());
  } catch (const ConfigError& e) {  // $RIG_HISTORY's database is the environment's mistake: said so
    // A stop while it waited for a lock ended the wait (set_lock_wait_stop): the run was stopped.
    if (cancel.requested())
      throw AbortedError("aborted before anything was powered or moved: " + cancel.token().reason() + " (" + e.what() + ")");
    std::string why = e.what();
    const char* env = std::getenv("RIG_HISTORY");
    if (a.db.empty() && env && url == env) why = "RIG_HISTORY: " + why;
    // A resume's database is the one its run started with (a re-test: "a typo?" for a folder
    // removed since, with no word of where the name came from or what overrides it).
    else if (a.db_from_run_json)
      why += " (the database the run started with, from " + a.resume +
             "/run.json; --db URL with --resume records into another, --no-history into none)";
    if (!a.dry_run || !dynamic_cast<const history::LockedError*>(&e)) throw ConfigError(why);
    std::cerr << error_prefix(e) << why << " (the dry run goes on with its other checks and its plan, "
              << "and exits 2: a " << (a.resume.empty() ? "run" : "resume")
              << " started now would stop here, before anything opens)\n";
    return true;
  }
  return false;
}

// --serial with --resume guards the resume: it must name the run's DUT, the one given when the
// run started or, without that, the one its DUT reported (the checkpoint's). After read_run_json.
void check_the_resumes_serial(const RunArgs& a) {
  if (a.resume_serial.empty()) return;
  const std::string runs_dut = a.serial.empty() ? reported_serial(a.resume) : a.serial;
  if (runs_dut.empty())
    throw ConfigError(fmt::format("--serial {}: the run in {} was started without --serial and no DUT has "
                                  "reported its serial yet; the serial is checked at bring-up",
                                  a.resume_serial, a.resume));
  if (runs_dut != a.resume_serial)
    throw ConfigError(fmt::format("--serial {}: the run in {} is of DUT '{}'", a.resume_serial, a.resume, runs_dut));
}

// Devices that did not open (make_hardware or make_emulated threw `e`): the run's files say so
// (write_files_of_unopened_run) and the technician is told how the run goes on; a configuration
// error is fixed and started anew. The caller rethrows `e` (main: exit 4 hardware, 2 configuration).
// kept, planned: phases complete (a resume's) and in the plan.
void end_with_devices_unopened(const std::exception& e, const RunArgs& a, const acceptance::Profile& p,
                               const toml::table& hw, const std::string& started, const std::optional<seal::Key>& key,
                               std::size_t kept, std::size_t planned, const LogLoss& loss,
                               const std::string& resume_key, spdlog::logger& log) {
  log.error("devices not opened: {}", e.what());
  const bool config_error = dynamic_cast<const ConfigError*>(&e) != nullptr;
  // A log the disk refused lines of stops this ending's resume as any stopped run's (a review:
  // this path alone offered it).
  const std::string log_missing = config_error ? std::string() : loss.said();
  write_files_of_unopened_run(a, p, hw, started,
                              log_missing.empty() ? std::string(e.what()) : e.what() + std::string("; ") + log_missing,
                              config_error, key, log);
  // The folder stays for a resume once the devices can be opened (a new run into it is refused
  // "use --resume"), so it is said as after any stop (a review: no hint). A configuration
  // error is fixed and started anew.
  if (!log_missing.empty())
    say_no_resume(log_missing_lines_why(a.out), log);
  else if (!config_error)
    say_how_to_continue(a.out, kept, planned, ": the devices did not open", resume_key, log);
  // The closing line every other ending has (a technician's review: this one went from "to
  // continue" to the attempt's end), with main()'s exit code for the error thrown on.
  const bool aborted = dynamic_cast<const AbortedError*>(&e) != nullptr;
  log.info("outcome ERROR (exit {})", config_error ? kExitUsage : aborted ? kExitAborted : kExitHardware);
}

// After the passport: why the run has no resume and how its ending is finished, or after a stop
// how the run goes on (what is kept, what its resume repeats).
void say_what_follows(const RunArgs& a, const RunResult& res, bool emulated, const std::string& no_resume_why,
                      const std::string& resume_key, spdlog::logger& log) {
  // After a stop, what is kept and how to go on, where the technician looks (a review: only
  // `--dry-run --resume` said so). A configuration error is fixed and started anew, not resumed.
  if (!no_resume_why.empty()) {  // the hint said "19 of 19 phases kept", and that resume was exit 2 (a review)
    say_no_resume(no_resume_why, log);
    say_how_to_finish(a.out, resume_key, log);
  } else if ((res.outcome == RunOutcome::Aborted || res.outcome == RunOutcome::Error) && !res.config_error) {
    // An emulated run's injected sample losses are repeated by its resume (run.json's faults):
    // one that ended the run in ERROR ends the resume the same way (a line integrator's review:
    // each resume offered "to continue" and added another ERROR ending).
    const std::string drops = fmt::format("{}", fmt::join(sample_losses(a.inject), ", "));
    offer_a_resume(a.out, res.checkpointed, res.phases.size(),
                   res.outcome == RunOutcome::Error && emulated && !drops.empty()
                       ? "; its resume repeats run.json's faults (" + drops + "), so a loss that ended this run in "
                         "ERROR ends it so again"
                       : std::string(),
                   resume_key, log);
  }
}

struct TakenFolder {
  // The folder is this run's own (the default one it claimed, or one it creates), so a "no" at
  // the prompts may remove it; a folder the user made stays.
  bool made_here = false;
  bool taken_over = false;  // a stopped start's folder (only_a_start), taken over
};
// The run's folder (a.out; made under runs/ when not given) made ready for the run or its resume:
// a new run's takes its lock (`folder_lock`; a resume's was taken before its folder was read), an
// earlier run there refused, a stopped start taken over.
// Before the operator is asked anything: no one should answer the prompts of a run that cannot start.
TakenFolder take_the_folder(RunArgs& a, const acceptance::Profile& p, std::optional<FolderLock>& folder_lock,
                            bool sealed) {
  TakenFolder taken;
  taken.made_here = a.out.empty();
  if (a.out.empty()) a.out = default_run_folder(folder_name_part(a.serial.empty() ? p.name : a.serial));
  const char* option = a.resume.empty() ? "--out" : "--resume";
  refuse_an_unwritable_place(a.out, option);
  (void)check_room(a.out, option, p, !a.resume.empty());
  // Before the operator is asked anything, and before prepare_run_folder's write probe touches
  // the earlier run's folder (nor a folder another run holds: its lock is taken first).
  if (a.resume.empty()) {
    std::error_code ec;
    taken.made_here = taken.made_here || !fs::exists(a.out, ec);
    // A folder a live run holds says so first (it said "holds an earlier run: use --resume",
    // which then failed on the same lock: a review).
    if (fs::is_directory(a.out, ec)) folder_lock.emplace(a.out, "--out " + a.out);
    taken.taken_over = refuse_an_earlier_run(a.out, p.source);
    if (taken.taken_over) {
      if (!a.quiet) std::cerr << "rig: note: " << taken_over_note(a.out) << "\n";
      // Its staging files go: a seal.json.tmp stayed beside an unsealed run's records (a review).
      for (const char* f : {"profile.toml.tmp", "run.json.tmp", "seal.json.tmp"}) fs::remove(fs::path(a.out) / f, ec);
    }
    refuse_a_folder_a_new_run_cannot_own(a.out, "--out", sealed, taken.taken_over);
  }
  prepare_run_folder(a.out, option);
  if (a.resume.empty()) {
    if (!folder_lock) folder_lock.emplace(a.out, "--out " + a.out);
    refuse_an_earlier_run(a.out, p.source);  // again, now that no other run can start here: one may have ended since
  }
  refuse_non_files(a.out, !a.resume.empty());
  return taken;
}

int do_run_watched(RunArgs a, CancelSource& cancel) {
  // A stop that comes while the history database waits for another writer's lock ends that wait
  // 2 s after it began (a review: a SIGTERM in the ending's wait held the exit 10 s).
  history::set_lock_wait_stop([stop = cancel.token()] { return stop.requested(); });
  // The station's key, and a resumed folder's seal, before anything in the folder is read.
  const std::optional<seal::Key> key = station_key(a.seal_key, a.seal_key_given);
  const std::string resume_key = resume_key_words(a, key.has_value());  // in every `to continue:` line
  require_utf8_paths(a);
  // One process per run folder (two runs or resumes of one folder would interleave their files):
  // held from here to the end of the run; a new run's folder is taken once it exists (below).
  std::optional<FolderLock> folder_lock;
  bool final_seal = false;  // a sealed final outcome (final_outcome_of) whose ending stopped after its seal
  if (!a.resume.empty()) {
    if (a.dry_run) FolderLock::check_free(a.resume, "--resume " + a.resume);
    else if (path_kind(a.resume, "--resume") == PathKind::directory) folder_lock.emplace(a.resume, "--resume " + a.resume);
    refuse_non_files(a.resume, true);
    final_seal = check_seal_before_resume(a.resume, key, fs::exists(a.resume + "/" + kEndingPending),
                                          !earlier_log_missing_lines(a.resume).empty());
    refuse_records_without_checkpoint(a.resume);
  }

  // A resumed run takes its profile and invocation from the run folder.
  nlohmann::json invocation;
  if (!a.resume.empty()) {
    const std::string inv_path = a.resume + "/run.json";
    if (path_kind(inv_path, "--resume") == PathKind::missing) throw ConfigError(inv_path + ": not a run folder (no run.json)");
    a.out = a.resume;
    invocation = read_run_json(a.resume, a);
    a.profile = a.resume + "/profile.toml";
    check_the_resumes_serial(a);
  }
  std::string profile_source;
  std::vector<std::string> dropped_limits;
  const toml::table profile_table = acceptance::load_profile_table(a.profile, profile_source, &dropped_limits);
  acceptance::Profile p = acceptance::parse_profile(profile_table, profile_source);
  const std::string profile_text = p.source.rfind("builtin:", 0) == 0
                                       ? acceptance::builtin_profile_text(p.source.substr(8))
                                       : file_text(p.source);
  a.profile_sha256 = seal::sha256_hex(profile_text);
  // Values a derived profile left without limits cannot fail the run: said before it starts
  // (an automation review: a base's GOST limits gone with its blocks, PASS without a word).
  const std::string unjudged = acceptance::unjudged_blocks_note(p, dropped_limits);
  if (a.resume.empty()) acceptance::check_profile_names_itself(profile_table, profile_source);
  if (!a.resume.empty()) check_the_folders_profile(a.resume, invocation, p);
  // The profile's [plant] is the emulated plant's own section: checked here, --dry-run included,
  // on every plant: a profile is shared by hardware and emulated runs, and a typo there must not
  // wait for the next emulated run to be found (before any device opens).
  const toml::table& plant_cfg = plant::plant_section(profile_table);
  const double emulated_rate_hz = plant::validate_plant_section(plant_cfg);
  if (a.plant == "emulated") check_emulated_rate(profile_table, profile_source, p, emulated_rate_hz);
  toml::table hw;
  if (a.plant == "hardware") hw = load_hardware_file(a.hardware, kRunSections);
  check_serial_source(a, hw, plant_cfg);
  const std::vector<Injection> injections = parse_injections(a.inject);
  if (!injections.empty() && a.plant != "emulated") throw ConfigError("--inject works with the emulated plant only");

  // The mount's angles before the phases are planned: each move's planned time follows them.
  if (a.plant == "hardware") {
    apply_procedure_angles(hw, p);
    // [dut.design]: the DUT type's loop, the loop figures' labelled fallback without a loop test.
    // Before the phases are planned (the loop figures' title names it: the plan said "no
    // [dut.design]" beside one) and whether or not a device opens (a resume may only compute).
    p.design_model = acceptance::read_design_model(*cfg::get_table(hw, "dut", true));
  }
  check_procedure_angles_in_travel(a, hw, plant_cfg, p);
  const DutLinkOptions dut = dut_link_options(a, hw, plant_cfg);
  check_stream_rate(a, dut.stream, p);
  acceptance::ProcedureState state(p);  // what the phases hand on; checkpointed with every phase
  const std::vector<Phase> phases = acceptance::build_phases(p, state, planned_table_timing(a, hw, plant_cfg), dut.can);
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  // A profile that judges nothing (no limits, no class table: a truncated file, a [limits]
  // renamed) would PASS every DUT with every value UNSET (a review): refused before anything.
  if (std::none_of(values.all().begin(), values.all().end(),
                   [](const Measurement& m) { return m.limits.has_value() || m.required; }))
    throw ConfigError(fmt::format("profile {}: no value has limits (no [limits] table, no [[classes]]): a run would "
                                  "PASS with nothing judged; give the limits it is to judge by",
                                  shown_text(p.source)));
  const nlohmann::json identity = run_identity(p, a);
  TerminalView view(stderr, a.quiet);
  // A history URL this rig cannot open (an unknown scheme, no file) is a typo to name now, not
  // an error in run.log after the DUT was measured and its result left out of the history.
  if (!a.no_history && !a.run_history_db.empty() && a.db.empty() &&
      !history::same_database(history_url(a, hw), a.run_history_db))
    a.history_left_behind = fmt::format(
        "the run records into {} (run.json's history_db, as it resolved when the run started); this resume's is {} "
        "($RIG_HISTORY, the rig config or the default here): {} keeps the earlier ending; give --db with that URL "
        "(its password too) to record there",
        a.run_history_db, history::mask_password(history_url(a, hw)), a.run_history_db);
  const bool history_locked = check_the_history(a, hw, cancel);
  if (!a.resume.empty()) {
    if (const auto rc = finish_pending_ending(a, hw, key, final_seal, values))
      return a.dry_run ? (history_locked ? kExitUsage : *rc) : the_passports_exit(*rc);
    refuse_to_drop_an_interrupted_ending(a);
  }
  if (a.dry_run)
    return print_dry_run(a, hw, plant_cfg, p, dut, phases, values, state, identity, key.has_value(), unjudged,
                         history_locked);
  if (!a.quiet)
    for (const std::string& n : faults_past_the_plan(injections, planned_device_s(phases)))
      std::cerr << "rig: note: " << n << "\n";
  // The table next, before a folder is made: one process at a time commands a station's table,
  // held to the run's end (app/table_lock.hpp; a `rig table move` from another terminal turned
  // the DUT during a recording).
  // The drive's identity is looked up once (a host name resolves): the lock and the backends'
  // stop watch use the same key.
  // A resume takes it once its checkpoint says a phase left uses the devices (below).
  std::string table_id;
  std::optional<TableLock> table_lock;
  auto lock_the_table = [&] {
    if (a.plant == "hardware")
      table_lock.emplace(table_id = modbus::table_identity(*cfg::get_table(hw, "table", true)),
                         a.resume.empty() ? "rig run" + (a.out.empty() ? std::string() : " --out " + shown_text(a.out))
                                          : "rig run --resume " + shown_text(a.resume));
  };
  if (a.resume.empty()) lock_the_table();
  const TakenFolder folder = take_the_folder(a, p, folder_lock, key.has_value());
  if (a.resume.empty()) refuse_a_run_log_it_cannot_write(a.out);  // a stopped start's, taken over
  // A resume's checkpoint, with the captures it names, is checked before the operator is asked
  // anything and before any device opens.
  std::shared_ptr<spdlog::logger> log;
  const auto log_loss = std::make_shared<LogLoss>();  // lines of run.log the disk refused
  Resumption resumed;
  const std::vector<std::string>& completed = resumed.completed;
  if (!a.resume.empty()) {
    // A finished run's folder is left as it is, its log included (a refused resume wrote into a
    // PASS run's log, a review); a sealed folder's verdict is its seal's (checked above).
    if (!key) refuse_a_final_verdict(a.out);
    refuse_a_log_missing_lines(a.out);
    // After those: a finished run's or a log-loss ending's folder is refused as such, not sent to
    // make its run.log writable for a resume it has not (a review).
    refuse_a_run_log_it_cannot_write(a.out);
    log = run_log_or_say(a, log_loss, "the resume did not start: nothing was powered or moved, the folder is as it was",
                         resume_key);
    const std::string unended = earlier_attempt_unended(a.out);  // read before this attempt's first line
    log->info("rig {} run: profile {} ({}), plant {}, out {}: resuming", RIG_VERSION, p.name, shown_text(p.source), a.plant,
              shown_text(a.out));
    say_where_the_account_broke_off(unended, *log);
    try {
      resumed = Executive::read_checkpoint(a.out, phases, values, state, identity, *log, true);
    } catch (const std::exception& e) {  // the log says why the resume did not happen (it said only "resuming")
      // In run.log only: the console gets it as the command's own error line (it came twice: a
      // line integrator's review).
      const auto console = log->sinks().front();  // make_logger's order: the console, then run.log
      const auto level = console->level();
      console->set_level(spdlog::level::off);
      log->error("resume refused: {}", e.what());
      console->set_level(level);
      throw;
    }
  }
  const bool devices_needed = devices_left(phases, completed.size());
  if (!a.resume.empty() && devices_needed) try {
      lock_the_table();
    } catch (const std::exception& e) {  // the resume's log says why it did not start (it said only "resuming")
      log->info("resume not started: {}; the folder is as it was", e.what());
      throw;
    }
  double planned_s = 0;
  for (std::size_t i = completed.size(); i < phases.size(); ++i) planned_s += phases[i].planned_s;
  // The plan first: the operator answers knowing what the run will do (it came after the answers,
  // once the devices were open: a technician's review).
  view.plan(phases, completed.size());
  std::vector<std::string> confirmed;
  try {
    if (devices_needed) confirmed = operator_prompts(a, p, planned_s, completed.size(), cancel.token());
  } catch (const std::exception& e) {
    // Declined (or no terminal to ask on, and no --yes) before the run started: nothing was
    // written, and a new run's folder goes too (a refusal for want of a terminal left it: a review).
    // A resume's log says the resume did not start (it ended at "resuming").
    if (log) log->info("resume not started: {}; the folder is as it was", e.what());
    std::error_code ec;
    if (a.resume.empty() && folder.made_here) fs::remove(a.out, ec);  // only while empty
    throw;
  }
  if (!a.resume.empty()) record_an_interrupted_ending(a, hw, *log);
  // The run's own wall time, for the plant's speed line: the operator's time at the prompts is not
  // the emulation's (a review read 105x real time where run.log spans 0.18 s of a 2.18 s figure).
  const auto wall_start = std::chrono::steady_clock::now();

  if (a.resume.empty()) {
    // The folder carries everything a resume needs.
    write_file_atomic(a.out + "/profile.toml", profile_text);
    invocation = new_run_invocation(a, hw, p);
    write_file_atomic(a.out + "/run.json", invocation.dump(2));
    if (key) seal_run_folder(a.out, *key, files_of_the_run(state.slot()));  // a stop before the first phase resumes too
    log = run_log_or_say(a, log_loss, "the run did not start: nothing was powered or moved", resume_key);
    log->info("rig {} run: profile {} ({}), plant {}, out {}", RIG_VERSION, p.name, shown_text(p.source), a.plant,
              shown_text(a.out));
    // The earlier start's run.json is replaced: its taking over is on the record (a review: said on
    // the terminal only, and not at all with --quiet).
    if (folder.taken_over) log->info("{}", taken_over_note(a.out));
  }
  for (const std::string& q : confirmed) log->info("operator confirmed: {} yes", q);
  if (table_lock && !table_lock->held())
    log->warn("{}", table_lock->unlocked_warning());
  if (folder_lock && !folder_lock->held())
    log->warn("the run folder could not be locked (its filesystem has no flock): a second run or resume of {} at the "
              "same time is not prevented",
              a.out);

  Backends b;
  try {
    b = !devices_needed            ? make_unopened(a.plant, state.slot().device_time_s.value_or(0.0), dut.can.link_loop_test_refusal)
        : a.plant == "hardware" ? make_hardware(hw, p, table_id)
                                : make_emulated(plant_cfg, a.serial);
  } catch (const std::exception& e) {
    end_with_devices_unopened(e, a, p, hw, invocation.value("started", iso8601_utc_now()), key, completed.size(),
                              phases.size(), *log_loss, resume_key, *log);
    throw;  // main() reports it with its exit code (4 hardware, 2 configuration)
  }
  int signal_at_end = 0;
  if (b.emulated) signal_at_end = apply_injections(*b.emulated, injections, cancel.token());
  Devices dev = b.devices();
  dev.io.on_estop([&cancel] { cancel.request("e-stop line opened"); });

  acceptance::RunOptions ro;
  if (!a.serial.empty()) ro.expected_serial = a.serial;

  Executive exec(dev, a.out, log, &view);
  if (!devices_needed) exec.without_devices(no_device_needed(a.plant, phases, completed.size()));
  exec.log_loss_from([log_loss] { return log_loss->said(); });
  if (!unjudged.empty()) log->warn("{}", unjudged);
  say_history_left_behind(a, *log);
  if (key)  // each checkpoint sealed with the captures beside it, before it replaces the last
    exec.on_checkpoint([&](const std::string& text) { seal_run_folder(a.out, *key, files_of_the_run(state.slot()), text); });
  const std::string started = invocation.value("started", iso8601_utc_now());
  // In emulation a resume rebuilds the plant as the checkpoint left it (app/fast_forward.hpp):
  // bring-up on a fresh plant, then the completed recordings replayed, so the resumed
  // passport equals the uninterrupted run's bit for bit. Hardware is only brought up again.
  // Where no phase left uses the devices no plant is made (make_unopened): nothing would meet the
  // rebuilt plant, and the replay needs room for its captures beside the run's (a line
  // integrator's review: a run stopped after its last phase, on a disk with less than that free,
  // failed every resume with ERROR).
  const bool fast_forward = b.emulated && !a.resume.empty();
  double replayed_s = 0;  // of the plant's figures below, what rebuilt it (nothing measured)
  std::uint64_t replayed_samples = 0;
  RunResult res = exec.run(
      [&](PhaseContext& c) {
        acceptance::bring_up(c, p, ro, state.slot());
        if (fast_forward && !completed.empty()) {  // bring-up's own device time is not the replay's
          const double t0 = b.emulated->clock().now_s();
          const std::uint64_t n0 = b.emulated->samples_generated();
          fast_forward_emulated(c, p, completed, *log);
          replayed_s = b.emulated->clock().now_s() - t0;
          replayed_samples = b.emulated->samples_generated() - n0;
        }
      },
      phases, values, state, cancel.token(), resumed, identity);
  // Faults that never met the run, said after a run that was not stopped; not where the resume
  // replayed nothing (no phase left used the devices): its device time and its drops are then only
  // bring-up's, and the faults fired in the run that recorded them (a code review: "run.json's
  // fault drop@1000:5 did not fire" on such a resume).
  if (b.emulated && res.outcome != RunOutcome::Aborted && (a.resume.empty() || fast_forward))
    say_faults_that_did_not_fire(*b.emulated, injections, !a.resume.empty(), *log);
  if (signal_at_end) {
    ::kill(::getpid(), signal_at_end);
    for (int i = 0; i < 500 && !cancel.requested(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }

  // Outputs: written whatever the outcome, so an aborted run keeps what it measured.
  PassportInfo info = passport_info(a, p, hw, started, state.slot().dut ? state.slot().serial() : a.serial);
  info.captures = state.slot().captures();  // what was recorded, not what lies in the folder
  if (state.slot().dut)
    for (const acceptance::SkippedStep& k : state.slot().dut->skipped) info.skipped.emplace_back(k.step, k.reason);
  std::sort(info.captures.begin(), info.captures.end());
  // A signal is taken until the passport is written: after the last phase it still aborts
  // the run (exit 3); the measurements stay judged as measured. After the passport is
  // written it is only logged (see the end of this function).
  if (cancel.requested() && (res.outcome == RunOutcome::Pass || res.outcome == RunOutcome::Fail)) {
    res.outcome = RunOutcome::Aborted;
    res.message = "aborted after the last phase: " + cancel.token().reason();
    log->error("{}", res.message);
  }
  // Stopped (a signal, the e-stop): the ending waits 2 s, not 10, for a history database another
  // process holds locked (rig/report/db.hpp set_lock_wait_ms); a row it cannot record is owed to
  // the resume (a line integrator's review: a SIGTERM'd run held its exit 10 s).
  if (res.outcome == RunOutcome::Aborted || cancel.requested()) history::set_lock_wait_ms(history::kStoppedLockWaitMs);
  const std::string no_resume_why = judge_the_records(a.out, res, state, key, *log_loss, *log);
  // Lines the ending refused so far are the checkpoint's word too: the passport that says it may be
  // refused next.
  if (!res.config_error) exec.record_the_log_loss();  // a configuration error's ending leaves the loss out (above)
  nlohmann::ordered_json passport;
  // An earlier ending's files (an ABORTED one, resumed) as they were before this ending: what it
  // cannot replace must not stand beside its ERROR ending.
  const std::optional<FileStamp> earlier_passport = stamp_of(a.out + "/passport.json"),
                                 earlier_analysis = stamp_of(a.out + "/analysis.json");
  try {
    passport = write_run_outputs(a, hw, info, res, values, state.slot(), key, *log);
  } catch (const std::exception& e) {  // a full disk, a folder made read-only: the log says how it ended
    end_short_of_files(e, a, hw, info, res, values, exec, earlier_passport, earlier_analysis, dev.io, no_resume_why,
                       *log_loss, resume_key, *log);
    throw;
  }
  dev.io.set_lamp(Lamp::Running, false);
  dev.io.set_lamp(res.outcome == RunOutcome::Pass ? Lamp::Pass : Lamp::Fail, true);
  say_the_passport(passport, info.out_dir);
  if (b.emulated)
    say_the_plants_speed(*b.emulated, std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(),
                         replayed_s, replayed_samples, *log);
  log->info("outcome {} (exit {})", to_string(res.outcome), res.exit_code());
  say_what_follows(a, res, b.emulated != nullptr, no_resume_why, resume_key, *log);
  if (cancel.requested() && res.outcome != RunOutcome::Aborted)
    log->warn("{} after the passport was final: outcome {} stands (exit {})", cancel.token().reason(),
              to_string(res.outcome), res.exit_code());
  return the_passports_exit(res.exit_code());
}

}  // namespace

void add_run(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("run", "Run the U10/U20 acceptance procedure and write the passport");
  // The codes a script branches on, in the help as in `rig report --help` (a technician's review).
  sub->footer("Exit codes: 0 PASS; 1 FAIL (a value outside its limits, or a limited value not measured); 2 usage or "
              "configuration error, found before any device opens (file, line and value named) or at bring-up (a DUT "
              "reporting another --serial, U10/U20 outside the table's travel once homed) or in a recording (a DUT "
              "streaming at another rate than rate_hz), or a table or run "
              "folder another rig process holds; 3 aborted (a signal, the e-stop input, the operator); 4 hardware or "
              "link fault, or a run folder that cannot hold the run's records. A verdict is final once the run "
              "folder holds no .ending-pending (README, \"On a production line\").");
  auto a = std::make_shared<RunArgs>();
  // Real hardware is named by its file, not here: `--plant hardware` said only "not in
  // {emulated}" (a review).
  auto* plant = sub->add_option("--plant", a->plant, "Plant to run on (emulated; real hardware: --hardware FILE)")
                    ->check(CLI::Validator(
                        [](std::string& v) {
                          if (v == "emulated") return std::string();
                          std::string lower = v;
                          for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
                          const bool hardware = lower.rfind("hardware", 0) == 0 || lower.find(".toml") != std::string::npos;
                          return "'" + shown_ascii(v) + "' is not a plant: give emulated" +
                                 (hardware ? std::string(", or, for real hardware, --hardware FILE alone, without "
                                                         "--plant (the hardware file describes the table, the DUT link "
                                                         "and the GPIO lines)")
                                           : std::string());
                        },
                        "emulated"));
  sub->add_option("--hardware", a->hardware, "Run on real hardware described by this TOML file")
      ->check(existing_file())
      ->excludes(plant);
  sub->add_option("--profile", a->profile, "Profile: paper, ci or a TOML file")->capture_default_str();
  sub->add_option("--serial", a->serial,
                  "DUT serial number, 1-32 printable ASCII: on hardware the DUT must report it; the emulated DUT "
                  "takes it")
      ->check(serial_validator());
  // A folder typed with a trailing slash (`--resume c5/`, a shell's completion) is the folder:
  // its files are named c5/checkpoint.json in messages, not c5//checkpoint.json (a review).
  const auto no_trailing_slash = CLI::Validator(
      [](std::string& v) {
        while (v.size() > 1 && v.back() == '/') v.pop_back();
        return std::string();
      },
      "");
  sub->add_option("--out", a->out, "Run folder (default runs/<serial|profile>-<YYYY-MM-DDTHHMMSSZ>, UTC)")
      ->transform(no_trailing_slash);
  sub->add_option("--resume", a->resume, "Continue the run in this folder after its last completed phase")
      ->check(existing_folder())
      ->transform(no_trailing_slash);
  sub->add_flag("--yes,-y", a->yes, "Skip operator confirmations (automated runs)");
  sub->add_flag("--dry-run", a->dry_run, "Print the plan and its duration; touch nothing");
  sub->add_flag("--quiet,-q", a->quiet, "Only the final table on the terminal");
  CLI::Option* db = sub->add_option("--db", a->db,
                  "History database URL (default: a resumed run's; else the hardware file's [history] url, "
                  "RIG_HISTORY, the rig config, $XDG_DATA_HOME or ~/.local/share: docs/history.md)");
  // Both at once is a contradiction to name, not a choice to make silently (a review: `--db
  // ftp://x --no-history` was accepted, the URL never read).
  sub->add_flag("--no-history", a->no_history, "Do not record the run in the history database")->excludes(db);
  sub->add_option("--seal-key", a->seal_key,
                  "Seal the run folder with this station key (HMAC-SHA256; docs/seal.md); a sealed run resumes only "
                  "with it")
      ->envname("RIG_SEAL_KEY");
  sub->add_option("--inject", a->inject,
                  "Emulated plant only: inject a fault (estop@T, sigint@T, sigterm@T, sigkill@T, sigint@end, "
                  "sigterm@end, drop@SEQ:COUNT; T in device seconds)");
  auto* serial = sub->get_option("--serial");
  auto* profile = sub->get_option("--profile");
  auto* hardware = sub->get_option("--hardware");
  auto* out = sub->get_option("--out");
  auto* inject = sub->get_option("--inject");
  sub->callback([a, &rc, plant, serial, profile, hardware, out, inject, sub] {
    if (!a->resume.empty()) {
      // A resume continues with the run folder's profile, plant and options (run.json,
      // profile.toml); one given again here would be ignored, so it is refused instead.
      for (const CLI::Option* o : {profile, plant, hardware, out, inject})
        if (o->count() > 0)
          throw ConfigError(o->get_name() + " cannot be given with --resume: the run continues with the profile, plant "
                                            "and options in " + a->resume + "/run.json and profile.toml");
      if (serial->count() > 0) a->resume_serial = a->serial;
    }
    a->seal_key_given = sub->get_option("--seal-key")->count() > 0;
    if (!a->hardware.empty()) a->plant = "hardware";
    rc = do_run(*a);
  });
}

}  // namespace rig::cli
