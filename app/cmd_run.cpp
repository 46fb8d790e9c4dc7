// `rig run`: the acceptance procedure, end to end, with a run folder holding
// the captures, checkpoint, passport.json, junit.xml, analysis.json,
// report.html and run.log. Exit codes per CONTRACTS.md.
#include <chrono>
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "plant/emulated/plant_config.hpp"
#include "plant/emulated/world.hpp"
#include "procedures/acceptance/analysis_doc.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "app/backends.hpp"
#include "app/commands.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/executive/passport.hpp"
#include "rig/executive/signals.hpp"
#include "rig/executive/terminal.hpp"
#include "rig/report/history.hpp"
#include "rig/report/report.hpp"

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
  std::string db;
  std::vector<std::string> inject;
  bool yes = false;
  bool dry_run = false;
  bool quiet = false;
  bool no_history = false;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Emulated-plant fault injection (tests and technicians' training):
// estop@T, sigint@T (a real SIGINT to this process), drop@SEQ:COUNT.
void apply_injections(plant::EmulatedPlant& w, const std::vector<std::string>& inj) {
  for (const std::string& s : inj) {
    const auto at = s.find('@');
    if (at == std::string::npos) throw ConfigError("--inject '" + s + "': expected KIND@ARG");
    const std::string kind = s.substr(0, at), arg = s.substr(at + 1);
    try {
      if (kind == "estop") {
        w.trip_estop_at(std::stod(arg));
      } else if (kind == "sigint") {
        w.at(std::stod(arg), [] { ::kill(::getpid(), SIGINT); });
      } else if (kind == "drop") {
        const auto c = arg.find(':');
        if (c == std::string::npos) throw ConfigError("--inject drop@SEQ:COUNT");
        w.inject_drop(static_cast<uint32_t>(std::stoul(arg.substr(0, c))),
                      static_cast<uint32_t>(std::stoul(arg.substr(c + 1))));
      } else {
        throw ConfigError("--inject '" + s + "': unknown fault (estop@T, sigint@T, drop@SEQ:COUNT)");
      }
    } catch (const std::logic_error&) {
      throw ConfigError("--inject '" + s + "': bad number");
    }
  }
}

bool confirm(const std::string& question) {
  std::cout << question << " [y/N] " << std::flush;
  std::string line;
  if (!std::getline(std::cin, line)) return false;
  return !line.empty() && (line[0] == 'y' || line[0] == 'Y');
}

// Operator prompts where a person must act; --yes skips them (automation).
void operator_prompts(const RunArgs& a, const acceptance::Profile& p) {
  if (a.yes) return;
  if (!::isatty(STDIN_FILENO)) {
    if (a.plant == "emulated") return;  // nothing to mount: unattended emulated runs need no confirmation
    throw ConfigError("operator confirmation needed (mount the DUT, confirm the table is clear): run with --yes "
                      "for unattended runs");
  }
  std::cout << fmt::format("Profile '{}': {}\nDevice time {}.\n", p.name, p.description,
                           TerminalView::hms(p.planned_total_s()));
  if (!confirm("Is the DUT mounted on the table with its connector fastened?"))
    throw AbortedError("operator did not confirm the DUT is mounted");
  if (!a.serial.empty() && !confirm("Is the serial number on the DUT's label " + a.serial + "?"))
    throw AbortedError("operator did not confirm the serial number");
  if (!confirm("Is the table clear of tools, cables and hands?"))
    throw AbortedError("operator did not confirm the table is clear");
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

// --db, else the hardware file's [history] url, else the rig config's default.
std::string history_url(const RunArgs& a, const toml::table& hw) {
  if (!a.db.empty()) return a.db;
  if (const toml::table* h = cfg::get_table(hw, "history"))
    if (h->contains("url")) return cfg::get_string(*h, "url");
  return history::default_db_url();
}

std::shared_ptr<spdlog::logger> make_logger(const std::string& out_dir, bool quiet) {
  auto file = std::make_shared<spdlog::sinks::basic_file_sink_mt>(out_dir + "/run.log", false);
  file->set_level(spdlog::level::debug);
  auto err = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  err->set_level(quiet ? spdlog::level::err : spdlog::level::warn);
  auto log = std::make_shared<spdlog::logger>("rig", spdlog::sinks_init_list{file, err});
  log->set_level(spdlog::level::debug);
  log->set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%-5l%$ %v");
  log->flush_on(spdlog::level::debug);
  return log;
}

int do_run(RunArgs a) {
  const auto wall_start = std::chrono::steady_clock::now();
  CancelSource cancel;
  SignalWatcher signals(cancel);  // before any backend thread exists

  // A resumed run takes its profile and invocation from the run folder.
  nlohmann::json invocation;
  std::string profile_text_path;
  if (!a.resume.empty()) {
    const std::string inv_path = a.resume + "/run.json";
    if (!fs::exists(inv_path)) throw ConfigError(inv_path + ": not a run folder (no run.json)");
    try {
      invocation = nlohmann::json::parse(slurp(inv_path));
    } catch (const std::exception& e) {
      throw ConfigError(inv_path + ": unreadable: " + e.what());
    }
    a.out = a.resume;
    a.plant = invocation.value("plant", "emulated");
    a.hardware = invocation.value("hardware", "");
    a.serial = invocation.value("serial", "");
    a.profile = a.resume + "/profile.toml";
  }
  std::string profile_source;
  const toml::table profile_table = acceptance::load_profile_table(a.profile, profile_source);
  acceptance::Profile p = acceptance::parse_profile(profile_table, profile_source);
  // The profile's [plant] is the emulated plant's own section: checked here, --dry-run included.
  const toml::table& plant_cfg = plant::plant_section(profile_table);
  if (a.plant == "emulated") plant::validate_plant_section(plant_cfg);
  toml::table hw;
  if (a.plant == "hardware") hw = load_hardware_file(a.hardware);

  std::vector<Phase> phases = acceptance::build_phases(p);
  TerminalView view(stderr, a.quiet);
  if (a.dry_run) {
    TerminalView plan_view(stdout);
    std::cout << fmt::format("rig run --dry-run: profile '{}' ({}) on the {} plant; nothing is touched.\n", p.name,
                             p.source, a.plant);
    plan_view.plan(phases);
    double total = 0;
    for (const auto& ph : phases) total += ph.planned_s;
    std::cout << fmt::format("Estimated duration: {} of device time{}\n", TerminalView::hms(total),
                             a.plant == "emulated" ? " (emulated: seconds of wall time)"
                                                   : fmt::format(", the same in wall time"));
    return kExitPass;
  }
  operator_prompts(a, p);

  if (a.out.empty())
    a.out = fmt::format("runs/{}-{}", a.serial.empty() ? p.name : a.serial, iso8601_utc_now());
  fs::create_directories(a.out);
  if (a.resume.empty()) {
    if (fs::exists(Executive::checkpoint_path(a.out)))
      throw ConfigError(a.out + " holds an earlier run (checkpoint.json): use --resume " + a.out + " or another --out");
    // The folder carries everything a resume needs.
    std::ofstream(a.out + "/profile.toml") << (p.source.rfind("builtin:", 0) == 0
                                                   ? acceptance::builtin_profile_text(p.source.substr(8))
                                                   : slurp(p.source));
    invocation = {{"plant", a.plant}, {"hardware", a.hardware.empty() ? "" : fs::absolute(a.hardware).string()},
                  {"serial", a.serial}, {"profile", p.name}, {"profile_source", p.source},
                  {"software", std::string("rig ") + RIG_VERSION}, {"started", iso8601_utc_now()}};
    write_file_atomic(a.out + "/run.json", invocation.dump(2));
  }
  auto log = make_logger(a.out, a.quiet);
  log->info("rig {} run: profile {} ({}), plant {}, out {}", RIG_VERSION, p.name, p.source, a.plant, a.out);

  Backends b = a.plant == "hardware" ? make_hardware(hw, p) : make_emulated(plant_cfg);
  if (b.emulated) apply_injections(*b.emulated, a.inject);
  else if (!a.inject.empty()) throw ConfigError("--inject works with the emulated plant only");
  Devices dev = b.devices();
  dev.io.on_estop([&cancel] { cancel.request("e-stop line opened"); });

  MeasurementSet values;
  acceptance::declare_values(p, values);
  nlohmann::json state = nlohmann::json::object();
  const nlohmann::json identity = {{"profile_digest", p.digest}, {"plant", a.plant}, {"serial", a.serial}};
  acceptance::RunOptions ro;
  if (!a.serial.empty()) ro.expected_serial = a.serial;

  view.plan(phases);
  Executive exec(dev, a.out, log, &view);
  const std::string started = invocation.value("started", iso8601_utc_now());
  RunResult res = exec.run([&](PhaseContext& c) { acceptance::bring_up(c, p, ro); }, phases, values, state,
                           cancel.token(), !a.resume.empty(), identity);

  // Outputs: written whatever the outcome, so an aborted run keeps what it measured.
  PassportInfo info;
  info.serial = state.value("serial", a.serial);
  info.profile = p.name;
  info.plant = a.plant;
  info.station = a.plant == "hardware" ? cfg_station(hw) : "emulated plant";
  info.started = started;
  info.finished = iso8601_utc_now();
  info.software = std::string("rig ") + RIG_VERSION;
  info.out_dir = fs::absolute(a.out).string();
  if (fs::is_directory(a.out + "/captures"))
    for (const auto& e : fs::directory_iterator(a.out + "/captures"))
      if (e.path().extension() == ".cap") info.captures.push_back("captures/" + e.path().filename().string());
  std::sort(info.captures.begin(), info.captures.end());
  const auto passport = make_passport(info, res, values);
  write_passport(a.out + "/passport.json", passport);
  write_file_atomic(a.out + "/junit.xml", junit_xml(info, res, values));
  write_file_atomic(a.out + "/analysis.json", acceptance::analysis_document(state).dump(1));
  try {
    report::write_report(a.out);
  } catch (const std::exception& e) {
    log->error("report.html not written: {}", e.what());
  }
  if (!a.no_history) {
    try {
      history::record_run(history_url(a, hw), nlohmann::json::parse(passport.dump()), info.out_dir);
    } catch (const std::exception& e) {
      log->error("history database not updated: {}", e.what());
    }
  }
  dev.io.set_lamp(Lamp::Running, false);
  dev.io.set_lamp(res.outcome == RunOutcome::Pass ? Lamp::Pass : Lamp::Fail, true);
  std::cout << "\n" << passport_table(passport);
  std::cout << fmt::format("run folder: {}\n", info.out_dir);
  if (b.emulated) {  // the emulation's own speed, as measured on this run
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    const double device = b.emulated->clock().now_s();
    const auto samples = b.emulated->samples_generated();
    const std::string line = fmt::format(
        "emulated plant: {:.1f} min of device time, {} DUT samples, in {:.2f} s wall: {:.0f}x real time, {:.2f} M "
        "samples/s",
        device / 60, samples, wall, device / wall, static_cast<double>(samples) / wall / 1e6);
    std::cout << line << "\n";
    log->info("{}", line);
  }
  log->info("outcome {} (exit {})", to_string(res.outcome), res.exit_code());
  return res.exit_code();
}

}  // namespace

void add_run(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("run", "Run the U10/U20 acceptance procedure and write the passport");
  auto a = std::make_shared<RunArgs>();
  auto* plant = sub->add_option("--plant", a->plant, "Plant to run on (emulated)")->check(CLI::IsMember({"emulated"}));
  sub->add_option("--hardware", a->hardware, "Run on real hardware described by this TOML file")
      ->check(CLI::ExistingFile)
      ->excludes(plant);
  sub->add_option("--profile", a->profile, "Profile: paper, ci or a TOML file")->capture_default_str();
  sub->add_option("--serial", a->serial, "Expected DUT serial number (the DUT must report it)");
  sub->add_option("--out", a->out, "Run folder (default runs/<serial|profile>-<time>)");
  sub->add_option("--resume", a->resume, "Continue the run in this folder after its last completed phase")
      ->check(CLI::ExistingDirectory);
  sub->add_flag("--yes,-y", a->yes, "Skip operator confirmations (automated runs)");
  sub->add_flag("--dry-run", a->dry_run, "Print the plan and its duration; touch nothing");
  sub->add_flag("--quiet,-q", a->quiet, "Only the final table on the terminal");
  sub->add_option("--db", a->db, "History database URL (default: rig config / ~/.local/share/rig/history.sqlite)");
  sub->add_flag("--no-history", a->no_history, "Do not record the run in the history database");
  sub->add_option("--inject", a->inject,
                  "Emulated plant only: inject a fault (estop@T, sigint@T, drop@SEQ:COUNT; T in device seconds)");
  sub->callback([a, &rc] {
    if (!a->hardware.empty()) a->plant = "hardware";
    rc = do_run(*a);
  });
}

}  // namespace rig::cli
