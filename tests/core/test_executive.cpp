// The executive against the in-process emulated plant: phases, checkpoints,
// resume, abort with the safe-state sequence, faults, and gap handling.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "analysis/allan.hpp"
#include "analysis/psd.hpp"
#include "plant/emulated/world.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/record.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/errors.hpp"
#include "rig/executive/executive.hpp"
#include "rig/executive/passport.hpp"
#include "rig/executive/terminal.hpp"

namespace fs = std::filesystem;
using namespace rig;

namespace {

struct Fixture {
  std::ostringstream logtext;
  std::shared_ptr<spdlog::logger> log;
  toml::table plant_cfg;
  std::unique_ptr<plant::EmulatedPlant> world;
  std::string out;

  explicit Fixture(const std::string& name) {
    log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
    log->set_pattern("%l %v");
    plant_cfg.insert("seed", 7);
    world = std::make_unique<plant::EmulatedPlant>(plant_cfg);
    out = fs::temp_directory_path() / ("rigexec-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(out);
    fs::create_directories(out);
  }
  Devices dev() { return {world->table(), world->dut(), world->io(), world->clock(), "emulated"}; }
};

void power_on(PhaseContext& c) {
  c.dev.io.set_dut_power(true);
  c.dev.table.home(c.cancel);
}

// A procedure state that is plain JSON (the acceptance procedure's is typed: state.hpp).
struct JsonState final : PhaseState {
  nlohmann::json j = nlohmann::json::object();
  nlohmann::json save() const override { return j; }
  void restore(const nlohmann::json& from, const std::vector<std::string>&, const std::string&) override { j = from; }
};

// Declares every phase's measures (as the procedure's declare_values does).
void declare(const std::vector<Phase>& phases, MeasurementSet& v,
             std::optional<std::pair<double, double>> limits = std::nullopt) {
  for (const auto& p : phases)
    for (const auto& m : p.measures) v.declare(m, limits);
}

}  // namespace

TEST(Executive, RunsPhasesInOrderAndCheckpointsEach) {
  Fixture f("order");
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<std::string> ran;
  std::vector<Phase> phases;
  for (const char* id : {"a", "b", "c"})
    phases.push_back({id, id, 1.0,
                      [&ran, id](PhaseContext& c) {
                        ran.push_back(id);
                        c.values.set(std::string("v_") + id, 1.0);
                        c.dev.clock.sleep_for(1.0, c.cancel);
                      },
                      {{std::string("v_") + id, "g", "test value"}}});
  MeasurementSet v;
  declare(phases, v);
  JsonState state;
  const auto r = ex.run(power_on, phases, v, state, CancelToken{}, false, {{"k", 1}});
  EXPECT_EQ(r.outcome, RunOutcome::Pass);
  EXPECT_EQ(ran, (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_TRUE(fs::exists(Executive::checkpoint_path(f.out)));
  EXPECT_FALSE(f.world->io().dut_power()) << "safe state at the end of every run";
}

TEST(Executive, AbortRunsSafeStateInOrderAndKeepsMeasurements) {
  Fixture f("abort");
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  CancelSource cs;
  std::vector<Phase> phases{
      {"first", "first", 1, [](PhaseContext& c) { c.values.set("kept", 42.0); }, {{"kept", "g", ""}}},
      {"second", "second", 1,
       [&cs](PhaseContext& c) {
         c.dev.dut.start_stream(c.cancel);
         cs.request("test abort");
         std::vector<Sample> buf(100);
         c.dev.dut.read(buf, c.cancel);  // must throw AbortedError promptly
         FAIL() << "read should have been cancelled";
       }},
      {"third", "third", 1, [](PhaseContext&) { FAIL() << "must not run after abort"; }}};
  MeasurementSet v;
  declare(phases, v);
  JsonState state;
  const auto r = ex.run(power_on, phases, v, state, cs.token(), false, {});
  EXPECT_EQ(r.outcome, RunOutcome::Aborted);
  EXPECT_EQ(r.exit_code(), kExitAborted);
  EXPECT_NE(r.message.find("test abort"), std::string::npos);
  ASSERT_NE(v.find("kept"), nullptr);
  EXPECT_EQ(*v.find("kept")->value, 42.0);
  EXPECT_EQ(r.phases[1].status, "aborted");
  EXPECT_EQ(r.phases[2].status, "pending");
  const std::string log = f.logtext.str();
  const auto t = log.find("safe state 1/3: stopping table");
  const auto s = log.find("safe state 2/3: stopping DUT stream");
  const auto p = log.find("safe state 3/3: DUT power off");
  ASSERT_NE(t, std::string::npos) << log;
  EXPECT_LT(t, s);
  EXPECT_LT(s, p);
  // The stop's fate, also when it went out (a client's "no halt sent by this client" after
  // another master's command may precede it).
  const auto delivered = log.find("safe state 1/3: stop delivered to the table");
  EXPECT_LT(t, delivered);
  EXPECT_LT(delivered, s);
  EXPECT_FALSE(f.world->io().dut_power());
}

// A stop that did not go out (not delivered, or not sent into a device that is not the configured
// drive) is said in run.log's safe state, not passed over before "safe state reached" (a review).
TEST(Executive, TheSafeStateLogsAStopThatDidNotGoOut) {
  Fixture f("stop-fate");
  struct Unsent final : RotaryTable {
    explicit Unsent(RotaryTable& t) : t_(t) {}
    TableStatus status() override { return t_.status(); }
    void home(const CancelToken& c) override { t_.home(c); }
    void move_to(double deg, const CancelToken& c) override { t_.move_to(deg, c); }
    void stop() noexcept override {}
    void quick_stop() noexcept override {}
    std::string describe() const override { return "unsent table"; }
    std::string stop_fate() const override { return "halt not sent: statusword (0x6041) reads 0x0401"; }
    RotaryTable& t_;
  } table(f.world->table());
  Devices d{table, f.world->dut(), f.world->io(), f.world->clock(), "emulated"};
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<Phase> phases{{"only", "only", 1, [](PhaseContext&) { throw HardwareError("table fault"); }}};
  MeasurementSet v;
  JsonState state;
  ex.run(power_on, phases, v, state, CancelSource().token(), false, {});
  const std::string log = f.logtext.str();
  const auto fate = log.find("safe state 1/3: halt not sent: statusword (0x6041) reads 0x0401");
  ASSERT_NE(fate, std::string::npos) << log;
  EXPECT_LT(fate, log.find("safe state 2/3"));
}

TEST(Executive, ResumeSkipsCompletedPhasesAndRestoresState) {
  Fixture f("resume");
  int runs_a = 0, runs_b = 0;
  JsonState st;
  std::vector<Phase> phases{{"a", "a", 1,
                             [&](PhaseContext& c) {
                               ++runs_a;
                               st.j["from_a"] = 5;
                               (void)c;
                             }},
                            {"b", "b", 1, [&](PhaseContext&) {
                               ++runs_b;
                               throw HardwareError("link died");
                             }}};
  const nlohmann::json id{{"profile", "x"}};
  std::string first_started, first_finished;  // when phase a ran, in the first attempt
  {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    const auto r = ex.run(power_on, phases, v, st, CancelToken{}, false, id);
    EXPECT_EQ(r.outcome, RunOutcome::Error);
    EXPECT_EQ(r.exit_code(), kExitHardware);
    first_started = r.phases[0].started;
    first_finished = r.phases[0].finished;
    ASSERT_FALSE(first_started.empty());
  }
  {  // A resume stopped during its bring-up: the checkpoint's phase is still kept (the passport
     // said every phase "pending": a review), the rest pending.
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    const auto r = ex.run([](PhaseContext&) { throw AbortedError("SIGINT received"); }, phases, v, st, CancelToken{},
                          true, id);
    EXPECT_EQ(r.outcome, RunOutcome::Aborted);
    EXPECT_EQ(r.phases[0].status, "skipped");
    EXPECT_EQ(r.phases[0].message, "completed in an earlier attempt (checkpoint)");
    EXPECT_EQ(r.phases[1].status, "pending");
  }
  phases[1].run = [&](PhaseContext&) {
    ++runs_b;
    EXPECT_EQ(st.j["from_a"], 5);
  };
  st.j = nlohmann::json::object();
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  MeasurementSet v;
  declare(phases, v);
  const auto r = ex.run(power_on, phases, v, st, CancelToken{}, true, id);
  EXPECT_EQ(r.outcome, RunOutcome::Pass);
  EXPECT_EQ(runs_a, 1) << "a completed phase is never repeated";
  EXPECT_EQ(runs_b, 2);
  EXPECT_EQ(r.phases[0].status, "skipped");
  // The kept phase keeps when it ran, from the checkpoint (its times were blank: a review).
  EXPECT_EQ(r.phases[0].started, first_started);
  EXPECT_EQ(r.phases[0].finished, first_finished);
  EXPECT_EQ(st.j["from_a"], 5);
  // A different identity refuses to resume.
  MeasurementSet v2;
  declare(phases, v2);
  EXPECT_THROW(ex.run(power_on, phases, v2, st, CancelToken{}, true, {{"profile", "other"}}), ConfigError);
  // A finished run has nothing to resume: refused, and no phase runs again.
  MeasurementSet v3;
  declare(phases, v3);
  try {
    ex.run(power_on, phases, v3, st, CancelToken{}, true, id);
    ADD_FAILURE() << "resuming a complete run must be refused";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("the run is complete"), std::string::npos) << e.what();
  }
  EXPECT_EQ(runs_a, 1);
  EXPECT_EQ(runs_b, 2);
  // Unless the caller allows it (a run with no verdict yet): every phase comes back completed.
  MeasurementSet v4;
  declare(phases, v4);
  spdlog::logger quiet("quiet");
  const auto all = Executive::read_checkpoint(f.out, phases, v4, st, id, quiet, true);
  EXPECT_EQ(all.completed.size(), phases.size());
}

struct ForgettingState final : PhaseState {
  nlohmann::json j = nlohmann::json::object();
  std::vector<std::string> forgotten;
  nlohmann::json save() const override { return j; }
  void restore(const nlohmann::json& from, const std::vector<std::string>&, const std::string&) override { j = from; }
  void forget(const std::string& id) override { forgotten.push_back(id); }
};

// A phase that measures on the device (declares measures, not from_records) has no record to
// compute its values again from: a resume never takes them from the checkpoint. It, and every
// phase after it, is returned as not completed, their values and state forgotten, and runs again.
TEST(Executive, AResumeMeasuresOnTheDeviceAgain) {
  Fixture f("measure-again");
  int records = 0, measures = 0, computes = 0;
  ForgettingState st;
  std::vector<Phase> phases{{"rec", "record", 1, [&](PhaseContext&) { ++records; }},
                            {"meas", "measure on the device", 1,
                             [&](PhaseContext& c) {
                               ++measures;
                               c.values.set("m", 3.0);
                             },
                             {{"m", "Hz", ""}}},
                            {"calc", "compute", 0,
                             [&](PhaseContext& c) {
                               ++computes;
                               c.values.set("v", 2.0);
                             },
                             {{"v", "g", ""}}, true}};
  const nlohmann::json id{{"profile", "x"}};
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  {
    MeasurementSet v;
    declare(phases, v);
    ASSERT_EQ(ex.run(power_on, phases, v, st, CancelToken{}, false, id).outcome, RunOutcome::Pass);
  }
  // The measured value edited in the checkpoint.
  auto cp = nlohmann::json::parse(std::ifstream(Executive::checkpoint_path(f.out)));
  cp["values"]["m"]["value"] = 99.0;
  std::ofstream(Executive::checkpoint_path(f.out)) << cp.dump();
  MeasurementSet v;
  declare(phases, v);
  spdlog::logger quiet("quiet");
  const auto done = Executive::read_checkpoint(f.out, phases, v, st, id, quiet, true);
  EXPECT_EQ(done.completed, std::vector<std::string>{"rec"});
  EXPECT_FALSE(v.find("m")->value.has_value()) << "forgotten, not read back";
  EXPECT_EQ(st.forgotten, (std::vector<std::string>{"meas", "calc"}));
  const auto r = ex.run(power_on, phases, v, st, CancelToken{}, done, id);
  EXPECT_EQ(r.outcome, RunOutcome::Pass);
  EXPECT_EQ(records, 1) << "the recording is kept";
  EXPECT_EQ(measures, 2) << "the device measures again";
  EXPECT_EQ(computes, 2);
  EXPECT_EQ(*v.find("m")->value, 3.0);
  EXPECT_EQ(r.phases[1].status, "done");
}

namespace {
// One phase whose body throws, run in a fresh folder: the result.
RunResult one_throwing_phase(const std::string& name, const std::function<void(PhaseContext&)>& body, bool from_records) {
  Fixture f(name);
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<Phase> phases{{"calc", "compute", 0, body, {{"v", "g", ""}}, from_records}};
  MeasurementSet v;
  declare(phases, v);
  JsonState st;
  return ex.run(power_on, phases, v, st, CancelToken{}, false, {});
}
}  // namespace

// A phase that computes from the run's records and finds them damaged (a ConfigError from the
// reader) found them changed while the run went on: an ERROR of the folder, not a configuration
// error (a review: loop-test.csv edited mid-run ended exit 2). A phase that is not from records
// keeps its ConfigError.
TEST(Executive, ARecordDamagedWhileTheRunWentOnIsNoConfigurationError) {
  for (const bool from_records : {true, false}) {
    const auto r = one_throwing_phase(from_records ? "records-changed" : "config-late",
                                      [](PhaseContext&) { throw ConfigError("state.loop_test.crc32: 1 does not match"); },
                                      from_records);
    EXPECT_EQ(r.outcome, RunOutcome::Error);
    EXPECT_EQ(r.config_error, !from_records);
    EXPECT_EQ(r.records_changed, from_records);  // no resume is offered for it (app/cmd_run.cpp)
    if (from_records) {
      EXPECT_EQ(r.exit_code(), kExitHardware) << r.message;
      EXPECT_EQ(r.message, "error: the run's records changed while it went on: state.loop_test.crc32: 1 does not match");
    }
  }
}

// A capture a from-records phase finds damaged (RecordsChangedError, procedure.cpp's
// load_capture) is the same: exit 4 and no resume offered (a review: the hint said "16 of 19
// phases kept" and the resume was refused).
TEST(Executive, ACaptureFoundDamagedByAPhaseOffersNoResume) {
  const auto r = one_throwing_phase(
      "capture-changed", [](PhaseContext&) { throw RecordsChangedError("captures/raw-U10.cap: 100 of 3600 samples"); },
      true);
  EXPECT_EQ(r.outcome, RunOutcome::Error);
  EXPECT_TRUE(r.records_changed);
  EXPECT_FALSE(r.config_error);
  EXPECT_EQ(r.exit_code(), kExitHardware);
  EXPECT_EQ(r.message, "error: captures/raw-U10.cap: 100 of 3600 samples");
}

// A phase that only computes from records (Phase::from_records) runs again on a resume: its
// checkpointed value is forgotten (an edited one is never taken), the recording before it is not
// repeated, and the checkpoint keeps its phases in order.
TEST(Executive, AResumeRunsTheComputingPhasesAgain) {
  Fixture f("recompute");
  int records = 0, computes = 0;
  JsonState st;
  std::vector<Phase> phases{{"rec", "record", 1, [&](PhaseContext&) { ++records; }},
                            {"calc", "compute", 0,
                             [&](PhaseContext& c) {
                               ++computes;
                               c.values.set("v", 2.0);
                             },
                             {{"v", "g", ""}}, true},
                            {"last", "record again", 1, [&](PhaseContext&) { throw HardwareError("link died"); }}};
  {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    EXPECT_EQ(ex.run(power_on, phases, v, st, CancelToken{}, false, {}).outcome, RunOutcome::Error);
  }
  const std::string cp = Executive::checkpoint_path(f.out);
  nlohmann::json j = nlohmann::json::parse(std::ifstream(cp));
  ASSERT_EQ(j["completed"], (nlohmann::json{"rec", "calc"}));
  j["values"]["v"]["value"] = 99.0;  // edited
  std::ofstream(cp) << j.dump();
  phases[1].run = [&](PhaseContext& c) {
    ++computes;
    EXPECT_FALSE(c.values.find("v")->value.has_value()) << "the checkpoint's value reached the phase";
    c.values.set("v", 2.0);
  };
  phases[2].run = [](PhaseContext&) { throw HardwareError("link died again"); };
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  MeasurementSet v;
  declare(phases, v);
  const auto r = ex.run(power_on, phases, v, st, CancelToken{}, true, {});
  EXPECT_EQ(records, 1) << "a recording is never repeated";
  EXPECT_EQ(computes, 2);
  EXPECT_EQ(r.phases[0].status, "skipped");
  EXPECT_EQ(r.phases[1].status, "done");
  EXPECT_EQ(*v.find("v")->value, 2.0);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(cp))["completed"], (nlohmann::json{"rec", "calc"}));
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(cp))["values"]["v"]["value"], 2.0);
}

// A resume stopped in a computing phase it runs again: the checkpoint still holds that phase
// (its records are kept), so the next resume starts from the same point and the hint's count
// is the checkpoint's (a review: "13 of 19 phases kept" where the dry run said 15); the value
// the stopped phase never set again says why it is missing, not an empty reason.
TEST(Executive, AResumeStoppedWhileComputingAgainKeepsTheCheckpointsPhases) {
  Fixture f("recompute-stop");
  JsonState st;
  std::vector<Phase> phases{{"rec", "record", 1, [&](PhaseContext&) {}},
                            {"calc", "compute", 0, [&](PhaseContext& c) { c.values.set("v", 2.0); }, {{"v", "g", ""}},
                             true},
                            {"last", "record again", 1, [&](PhaseContext&) { throw HardwareError("link died"); }}};
  {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    EXPECT_EQ(ex.run(power_on, phases, v, st, CancelToken{}, false, {}).checkpointed, 2u);
  }
  phases[1].run = [](PhaseContext&) { throw HardwareError("stopped while computing"); };
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  MeasurementSet v;
  declare(phases, v);
  const auto r = ex.run(power_on, phases, v, st, CancelToken{}, true, {});
  EXPECT_EQ(r.phases[1].status, "failed");
  EXPECT_EQ(r.checkpointed, 2u);
  MeasurementSet again;
  declare(phases, again);
  JsonState st2;
  spdlog::logger quiet("quiet");
  EXPECT_EQ(Executive::read_checkpoint(f.out, phases, again, st2, {}, quiet).completed.size(), r.checkpointed)
      << "what a dry run of the next resume counts";
  // Measured before, computed again from the kept records by a phase this resume did not finish:
  // said so, not "not measured" (a QA review).
  EXPECT_EQ(v.to_json()["v"]["reason"],
            "not computed again: the resume stopped before phase calc, which computes it from the kept records");
}

// Without devices (a resume with only computing phases left: app/backends.hpp make_unopened),
// nothing is brought up nor put in the safe state, and the log says why; a phase left that would
// use the devices is refused as a programming error, before any phase runs.
TEST(Executive, WithoutDevicesNothingIsBroughtUpOrMadeSafe) {
  Fixture f("no-devices");
  JsonState st;
  int computes = 0;
  std::vector<Phase> phases{{"rec", "record", 1, [](PhaseContext&) {}},
                            {"calc", "compute", 0,
                             [&](PhaseContext& c) {
                               ++computes;
                               c.values.set("v", 2.0);
                             },
                             {{"v", "g", ""}}, true}};
  {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    ASSERT_EQ(ex.run(power_on, phases, v, st, CancelToken{}, false, {}).outcome, RunOutcome::Pass);
  }
  f.logtext.str("");
  f.world->io().set_dut_power(true);  // as the safe state would find it, were it run
  int brought_up = 0;
  Devices d = f.dev();
  {
    Executive ex(d, f.out, f.log, nullptr);
    ex.without_devices("only computing is left");
    MeasurementSet v;
    declare(phases, v);
    spdlog::logger quiet("quiet");
    const Resumption from = Executive::read_checkpoint(f.out, phases, v, st, {}, quiet, true);  // all complete
    const auto r = ex.run([&](PhaseContext&) { ++brought_up; }, phases, v, st, CancelToken{}, from, {});
    EXPECT_EQ(r.outcome, RunOutcome::Pass) << r.message;
    EXPECT_EQ(computes, 2);
    EXPECT_EQ(brought_up, 0);
    EXPECT_TRUE(f.world->io().dut_power()) << "no safe state: nothing was opened";
    EXPECT_NE(f.logtext.str().find("no device opened: only computing is left"), std::string::npos) << f.logtext.str();
    EXPECT_EQ(f.logtext.str().find("safe state"), std::string::npos) << f.logtext.str();
  }
  // A checkpoint that no longer holds the recording: that phase would use the devices.
  nlohmann::json j = nlohmann::json::parse(std::ifstream(Executive::checkpoint_path(f.out)));
  j["completed"] = nlohmann::json::array();
  std::ofstream(Executive::checkpoint_path(f.out)) << j.dump();
  Executive ex(d, f.out, f.log, nullptr);
  ex.without_devices("only computing is left");
  MeasurementSet v;
  declare(phases, v);
  const auto r = ex.run([&](PhaseContext&) { ++brought_up; }, phases, v, st, CancelToken{}, true, {});
  EXPECT_EQ(r.outcome, RunOutcome::Error);
  EXPECT_EQ(r.message, "error: phase rec uses the devices, but none is open");
  // The log's level says it is an error once (it read "error error: ...").
  EXPECT_NE(f.logtext.str().find("\nerror phase rec uses the devices, but none is open\n"), std::string::npos)
      << f.logtext.str();
  EXPECT_EQ(computes, 2);
  EXPECT_EQ(brought_up, 0);
}

// Lines of run.log the disk refused after the last checkpoint (the safe state's, the ending's)
// are written into it as the run ends (Executive::record_the_log_loss): the passport that says so
// may be refused too. Not after a checkpoint write that failed: each write seals its text first,
// and a second failure would leave no seal holding the checkpoint on disk (session 66's review).
TEST(Executive, ALogLossAfterTheLastCheckpointIsWrittenIntoItButNotAfterAFailedWrite) {
  const std::string lost = "run.log is missing lines: the disk refused 2 line(s)";
  for (const bool refuse_second : {false, true}) {
    Fixture f(refuse_second ? "log-loss-refused" : "log-loss");
    std::vector<Phase> phases{{"a", "a", 0, [](PhaseContext& c) { c.values.set("v", 1.0); }, {{"v", "g", ""}}},
                              {"b", "b", 0, [](PhaseContext&) {}}};
    MeasurementSet v;
    declare(phases, v);
    JsonState st;
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    int seals = 0;
    ex.on_checkpoint([&](const std::string&) {
      if (++seals == 2 && refuse_second) throw std::runtime_error("seal.json.tmp: No space left on device");
    });
    ex.log_loss_from([&] { return seals >= 2 ? lost : std::string(); });  // lines refused after the first write
    const RunResult r = ex.run(power_on, phases, v, st, CancelToken{}, false, {});
    const nlohmann::json cp = nlohmann::json::parse(std::ifstream(Executive::checkpoint_path(f.out)));
    if (!refuse_second) {
      EXPECT_EQ(r.outcome, RunOutcome::Pass) << r.message;
      EXPECT_EQ(seals, 3) << "the two phases' checkpoints and the re-write";
      EXPECT_EQ(cp.value("log_missing_lines", ""), lost) << cp.dump();
      EXPECT_EQ(cp["completed"], (nlohmann::json{"a", "b"}));
    } else {
      EXPECT_EQ(r.outcome, RunOutcome::Error) << r.message;
      EXPECT_EQ(seals, 2) << "no re-write after the failed one";
      EXPECT_FALSE(cp.contains("log_missing_lines")) << cp.dump();
      EXPECT_EQ(cp["completed"], (nlohmann::json{"a"})) << "the first checkpoint, as its seal holds it";
    }
  }
}

TEST(Executive, EstopEdgeInTheEmulatedPlantAbortsTheRun) {
  Fixture f("estop");
  Devices d = f.dev();
  CancelSource cs;
  double t_edge = -1;
  bool power_at_edge = true;
  f.world->io().on_estop([&] {
    t_edge = f.world->clock().now_s();
    power_at_edge = f.world->io().dut_power();
    cs.request("e-stop line opened");
  });
  f.world->trip_estop_at(3.0);
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<Phase> phases{{"wait", "wait", 10, [](PhaseContext& c) { c.dev.clock.sleep_for(10.0, c.cancel); }}};
  MeasurementSet v;
  NoPhaseState st;
  const auto r = ex.run(power_on, phases, v, st, cs.token(), false, {});
  EXPECT_EQ(r.outcome, RunOutcome::Aborted);
  EXPECT_NE(r.message.find("e-stop"), std::string::npos);
  EXPECT_GE(t_edge, 2.99);
  EXPECT_LE(t_edge, 3.0) << "the edge is seen within one 10 ms slice";
  EXPECT_FALSE(power_at_edge) << "power goes off before the handler runs";
  EXPECT_FALSE(f.world->io().dut_power());
}

// On hardware `rig run --serial SN` checks the serial the DUT reports (in emulation the
// emulated DUT is given SN instead, RigCli.EmulatedDutTakesTheSerialGiven...). The check is
// the procedure's bring-up, the same code on either plant: here the emulated DUT keeps its
// own serial, as a real one does.
TEST(Executive, BringUpRejectsADutReportingAnotherSerial) {
  const auto prof = acceptance::load_profile("ci");
  Fixture f("serial");
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  acceptance::RunOptions ro;
  ro.expected_serial = "NOT-THIS-ONE";
  MeasurementSet v;
  acceptance::ProcedureState st(prof);
  const auto r =
      ex.run([&](PhaseContext& c) { acceptance::bring_up(c, prof, ro, st.slot()); }, {}, v, st, CancelToken{}, false, {});
  EXPECT_EQ(r.outcome, RunOutcome::Error);
  EXPECT_EQ(r.exit_code(), kExitUsage);
  EXPECT_NE(r.message.find("EMU-QPA-0001"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("NOT-THIS-ONE"), std::string::npos) << r.message;
  EXPECT_FALSE(f.world->io().dut_power()) << "the safe state follows the refusal";
}

TEST(Executive, CaptureGapBeyondTheLimitIsRetriedThenFailsThePhase) {
  auto prof = acceptance::load_profile("ci");
  prof.retries = 1;
  prof.max_lost_samples = 0;
  {
    Fixture f("gap-retry");
    Devices d = f.dev();
    MeasurementSet v;
    PhaseContext c{d, CancelToken{}, v, f.out, f.log, nullptr, {}};
    power_on(c);
    // Two seconds into the first attempt, five samples never arrive; the retry is clean.
    auto* w = f.world.get();
    w->at(c.dev.clock.now_s() + prof.settle_s + 2.0, [w] { w->inject_drop(w->next_seq() + 10, 5); });
    const auto r = acceptance::position_and_record(c, prof, Orientation::U10, 5.0, "g", "SN");
    EXPECT_EQ(r.attempts, 2);
    EXPECT_EQ(r.lost, 0u);
    EXPECT_TRUE(fs::exists(f.out + "/captures/g.cap.interrupted-1")) << "the failed attempt's capture is kept";
  }
  {
    Fixture f("gap-fail");
    Devices d = f.dev();
    for (uint32_t s = 0; s < 100000; s += 1000) f.world->inject_drop(s + 500, 2);  // every attempt loses samples
    MeasurementSet v;
    PhaseContext c{d, CancelToken{}, v, f.out, f.log, nullptr, {}};
    power_on(c);
    try {
      acceptance::position_and_record(c, prof, Orientation::U10, 5.0, "g", "SN");
      FAIL() << "expected HardwareError";
    } catch (const HardwareError& e) {
      EXPECT_NE(std::string(e.what()).find("samples lost"), std::string::npos) << e.what();
    }
  }
}

TEST(Executive, SameSeedGivesBitIdenticalSamples) {
  auto grab = [] {
    Fixture f("seed");
    Devices d = f.dev();
    MeasurementSet v;
    PhaseContext c{d, CancelToken{}, v, f.out, f.log, nullptr, {}};
    power_on(c);
    c.dev.dut.start_stream(c.cancel);
    std::vector<Sample> buf(2000);
    c.dev.dut.read(buf, c.cancel);
    return buf;
  };
  const auto a = grab(), b = grab();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].x_g, b[i].x_g) << i;
    ASSERT_EQ(a[i].y_g, b[i].y_g) << i;
  }
}

TEST(Measurements, SettingAnUndeclaredNameIsAnError) {
  MeasurementSet v;
  v.declare({"bias", "g", "formula (3)"});
  EXPECT_NO_THROW(v.set("bias", 1e-4));
  EXPECT_THROW(v.set("bais", 1e-4), std::logic_error) << "a typo must not become a new UNSET value";
  EXPECT_EQ(v.all().size(), 1u);
}

// A value a resume forgets (its phase runs again) and never reaches again reads as one never
// measured, not with an empty reason (a review: a resume aborted during `bias`).
TEST(Measurements, AForgottenValueIsNotMeasuredAgain) {
  MeasurementSet v;
  v.declare({"bias", "g", "formula (3)"}, std::make_pair(-1e-3, 1e-3));
  EXPECT_EQ(v.to_json()["bias"]["reason"], "not measured");
  v.set("bias", 2e-4, "");
  v.forget("bias");
  v.judge_all(false);
  EXPECT_EQ(v.to_json()["bias"]["reason"], "not measured");
  EXPECT_TRUE(v.to_json()["bias"]["value"].is_null());
  EXPECT_EQ(v.find("bias")->outcome, Outcome::Unset);
}

TEST(Measurements, ANullLimitedValueFailsACompletedRunWithItsReason) {
  MeasurementSet v;
  v.declare({"k", "g/h^0.5", "rate random walk"}, std::make_pair(0.0, 1e-3));
  v.declare({"q", "g*h", "quantisation"});  // no limits: a null stays UNSET
  v.set("k", std::nullopt, "not identifiable from this record");
  v.set("q", std::nullopt, "not identifiable");
  v.judge_all(false);  // a run that stopped early: not measured yet
  EXPECT_EQ(v.find("k")->outcome, Outcome::Unset);
  v.judge_all(true);
  EXPECT_EQ(v.find("k")->outcome, Outcome::Fail);
  EXPECT_EQ(v.find("q")->outcome, Outcome::Unset);
  EXPECT_TRUE(v.any_failed());
  const auto j = v.to_json();
  EXPECT_EQ(j["k"]["reason"], "required value not measured: not identifiable from this record");
  v.judge_all(true);  // judging is idempotent
  EXPECT_EQ(v.to_json()["k"]["reason"], j["k"]["reason"]);
  EXPECT_EQ(j["k"]["description"], "rate random walk");
  // A phase that measured what the value is read from, beyond the value's scale, says so instead
  // (the accuracy class of a B above every class); a new value clears it.
  v.set("k", std::nullopt, "B = 3e-5 g").null_verdict = "B exceeds every accuracy class";
  v.judge_all(true);
  EXPECT_EQ(v.find("k")->outcome, Outcome::Fail);
  EXPECT_EQ(v.to_json()["k"]["reason"], "B exceeds every accuracy class: B = 3e-5 g");
  v.set("k", std::nullopt, "no capture");
  v.judge_all(true);
  EXPECT_EQ(v.to_json()["k"]["reason"], "required value not measured: no capture");
}

// A value just outside its limits is shown with the digits that put it outside: it read
// "settling_time = 0.00314 s outside limits [0, 0.00314]" (an automation review).
TEST(Measurements, AFailureShowsTheDigitsThatPutTheValueOutside) {
  MeasurementSet v;
  v.declare({"settling_time", "s", "settling"}, std::make_pair(0.0, 0.00314));
  v.declare({"bias", "g", "bias"}, std::make_pair(-1e-3, 1e-3));
  v.set("settling_time", 0.0031400000000000004);
  v.set("bias", 2.5e-3);
  v.judge_all(true);
  EXPECT_EQ(v.find("settling_time")->verdict, "value 0.0031400000000000004 outside limits [0, 0.00314]");
  EXPECT_EQ(v.find("bias")->verdict, "value 0.0025 outside limits [-0.001, 0.001]") << "6 digits where they suffice";
  const std::string x = junit_xml(PassportInfo{}, RunResult{}, v);
  EXPECT_NE(x.find("settling_time = 0.0031400000000000004 s outside limits [0, 0.00314]"), std::string::npos) << x;
  EXPECT_NE(x.find("bias = 0.0025 g outside limits [-0.001, 0.001]"), std::string::npos) << x;
  EXPECT_NE(x.find("value=0.0031400000000000004 unit=s limits=[0, 0.00314]"), std::string::npos) << x;
  const std::string table = passport_table(make_passport(PassportInfo{}, RunResult{}, v));
  EXPECT_NE(table.find(" 0.0031400000000000004 "), std::string::npos) << table;
  EXPECT_NE(table.find("[0, 0.00314]"), std::string::npos) << table;
  const ShownOutside n = shown_outside(std::nan(""), 0, 1);
  EXPECT_EQ(n.value, "nan");
}

// A passing value beside its limits is shown so that it reads as inside them: the table's short
// forms put 0.0024224 beside [0, 0.00242] (a metrologist's review); far from a limit they stay.
TEST(Measurements, APassNearALimitShowsTheDigitsThatPutTheValueInside) {
  MeasurementSet v;
  v.declare({"rms_unfiltered", "g", "rms"}, std::make_pair(0.0, 0.0024224));
  v.declare({"bias", "g", "bias"}, std::make_pair(-1e-3, 1e-3));
  v.set("rms_unfiltered", 0.00242236);
  v.set("bias", -4.98316e-4);
  v.judge_all(true);
  ASSERT_EQ(v.find("rms_unfiltered")->outcome, Outcome::Pass);
  const std::string table = passport_table(make_passport(PassportInfo{}, RunResult{}, v));
  EXPECT_NE(table.find(" 0.00242236 "), std::string::npos) << table;
  EXPECT_NE(table.find("[0, 0.0024224]"), std::string::npos) << table;
  EXPECT_NE(table.find(" -0.00049832 "), std::string::npos) << table;  // the short forms where they are in order
  EXPECT_NE(table.find("[-0.001, 0.001]"), std::string::npos) << table;
}

TEST(Executive, OutcomesAreJudgedOnceTheSameAfterAResume) {
  // A required value without limits (the accuracy class with a class table): null fails.
  Fixture f("judge-resume");
  int runs_b = 0;
  std::vector<Phase> phases{
      {"a", "a", 1, [](PhaseContext& c) { c.values.set("klass", std::nullopt, "B exceeds every class"); },
       {{"klass", "-", "class"}}},
      {"b", "b", 1, [&](PhaseContext&) {
         if (++runs_b == 1) throw HardwareError("link died");
       }}};
  auto run = [&](bool resume) {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    v.declare(phases[0].measures[0], std::nullopt, /*required=*/true);
    NoPhaseState st;
    const auto r = ex.run(power_on, phases, v, st, CancelToken{}, resume, {});
    return std::make_pair(r, v.find("klass")->outcome);
  };
  const auto [first, o1] = run(false);
  EXPECT_EQ(first.outcome, RunOutcome::Error);
  EXPECT_EQ(o1, Outcome::Unset) << "a run that stopped early does not fail what it has not finished";
  const auto [resumed, o2] = run(true);
  EXPECT_EQ(resumed.outcome, RunOutcome::Fail);
  EXPECT_EQ(resumed.exit_code(), kExitFail);
  EXPECT_EQ(o2, Outcome::Fail);
}

TEST(Executive, ACancelAfterTheLastPhaseStillAborts) {
  Fixture f("late-cancel");
  Devices d = f.dev();
  CancelSource cs;
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<Phase> phases{{"last", "last", 1, [&cs](PhaseContext&) { cs.request("SIGINT received"); }, {{"klass", "-", ""}}}};
  MeasurementSet v;
  v.declare(phases[0].measures[0], std::nullopt, /*required=*/true);
  NoPhaseState st;
  const auto r = ex.run(power_on, phases, v, st, cs.token(), false, {});
  EXPECT_EQ(r.outcome, RunOutcome::Aborted);
  EXPECT_EQ(r.exit_code(), kExitAborted);
  EXPECT_NE(r.message.find("SIGINT"), std::string::npos);
  // Every phase ran: judged as a complete run (a required value not measured fails), as when the
  // signal comes after the verdict; rig report checks the same rule.
  EXPECT_EQ(v.find("klass")->outcome, Outcome::Fail);
  EXPECT_EQ(r.message, "aborted after the last phase: SIGINT received");
  EXPECT_NE(f.logtext.str().find("safe state reached"), std::string::npos);
}

TEST(Executive, DamagedCheckpointIsAConfigErrorNamingTheField) {
  Fixture f("damaged");
  std::vector<Phase> phases{{"a", "a", 1, [](PhaseContext& c) { c.values.set("va", 1.0); }, {{"va", "g", ""}}},
                            {"b", "b", 1, [](PhaseContext&) { throw HardwareError("stop here"); }}};
  {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    NoPhaseState st;
    ASSERT_EQ(ex.run(power_on, phases, v, st, CancelToken{}, false, {}).outcome, RunOutcome::Error);
  }
  const std::string cp = Executive::checkpoint_path(f.out);
  const auto good = nlohmann::json::parse(std::ifstream(cp));
  auto expect_refused = [&](nlohmann::json j, const std::string& field) {
    std::ofstream(cp) << j.dump();
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    declare(phases, v);
    NoPhaseState st;
    try {
      ex.run(power_on, phases, v, st, CancelToken{}, true, {});
      ADD_FAILURE() << "resumed from a damaged checkpoint: " << j.dump();
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(cp), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  auto j = good;
  j["values"] = nlohmann::json::object();
  expect_refused(j, "values.va");
  j = good;
  j["values"]["va"]["value"] = "1.0";
  expect_refused(j, "values.va.value");
  j = good;
  j["completed"] = {"b"};  // phases complete in order
  expect_refused(j, "completed[0]");
  j = good;
  j["completed"] = 5;
  expect_refused(j, "completed");
  j = good;
  j["schema"] = "rig.checkpoint/9";
  expect_refused(j, "schema");
  j = good;
  j.erase("state");
  expect_refused(j, "state");
  j = good;
  j["values"]["vb"] = j["values"]["va"];
  expect_refused(j, "values.vb");
  ASSERT_TRUE(good.contains("phase_times") && good["phase_times"].contains("a")) << good.dump();
  j = good;
  j["phase_times"]["a"]["started"] = "yesterday";
  expect_refused(j, "phase_times.a.started");
  j = good;
  j["phase_times"] = 5;
  expect_refused(j, "phase_times");
}

TEST(AnalysisCancel, ThePollHookStopsADeviationAndAWelchPromptly) {
  std::vector<double> x(3'600'000);  // the paper's raw capture: 1 h at 1 kHz
  uint64_t s = 1;
  for (double& v : x) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    v = static_cast<double>(s >> 11) * 0x1p-53 - 0.5;
  }
  analysis::DevOptions opt;
  opt.rate_hz = 1000;
  opt.taus = analysis::parse_tau_grid("log:100");
  std::atomic<int> calls{0};
  std::mutex mu;
  auto last = std::chrono::steady_clock::now();
  double max_gap_s = 0;
  opt.poll = [&] {
    ++calls;
    std::lock_guard lk(mu);
    const auto now = std::chrono::steady_clock::now();
    max_gap_s = std::max(max_gap_s, std::chrono::duration<double>(now - last).count());
    last = now;
  };
  const auto t0 = std::chrono::steady_clock::now();
  (void)analysis::deviation(x, opt);
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Polled per chunk of 16 k phase points and per tau. The longest stretch without a poll is
  // printed (as measured here); it bounds how late an abort is taken in the allan phase.
  std::printf("deviation over 3.6e6 points: %.3f s, %d polls, longest gap %.4f s\n", total_s, calls.load(),
              max_gap_s);
  EXPECT_GT(calls.load(), 100) << "too coarse to take an abort within ~0.1 s";
  EXPECT_LT(max_gap_s, 0.25) << "an abort in the allan phase would wait this long";
  opt.poll = [&calls] {
    if (++calls > 5) throw AbortedError("aborted: test");
  };
  calls = 0;
  EXPECT_THROW(analysis::deviation(x, opt), AbortedError);
  analysis::WelchOptions wo;
  wo.poll = [] { throw AbortedError("aborted: test"); };
  EXPECT_THROW(analysis::welch(x, 1000, wo), AbortedError);
}

TEST(ProcedureState, OneJsonFormRoundTripsAndReadsTheUntypedCheckpoints) {
  acceptance::DutState s;
  s.dut = acceptance::DutIdentity{"SN1", "fw 1.2", 24.5, {}};
  acceptance::Recorded r;
  r.capture = "captures/run01-U10.cap";
  r.samples = 2000;
  r.mean_x = 1e-4;
  r.mean_y = 2e-4;
  s.runs[1] = acceptance::RunMean{1, Orientation::U10, r};
  s.bias = acceptance::BiasState{1e-4, 2e-5, -1};
  r.capture = "captures/in-run-U10.cap";
  s.in_run = r;
  s.in_run_blocks = std::vector<acceptance::GostBlock>{{2.0, {1.0, 2.0}, 0.5}, {4.0, {1.5}, std::nullopt}};
  s.analysis = nlohmann::json{{"allan", {{"x", 1}}}};
  const nlohmann::json j = acceptance::to_json(s);
  EXPECT_EQ(acceptance::to_json(acceptance::dut_state_from_json(j)), j);
  // Every recorded capture carries the same keys, wherever it appears.
  for (const auto* rec : {&j["runs"]["1"], &j["in_run"]})
    for (const char* k : {"capture", "n", "lost", "gaps", "duplicates", "attempts", "mean_g", "mean_y_g"})
      EXPECT_TRUE(rec->contains(k)) << k;
  EXPECT_EQ(s.captures(), (std::vector<std::string>{"captures/run01-U10.cap", "captures/in-run-U10.cap"}));
  // A checkpoint written before the state was typed (no duplicates, no means on in_run) still reads.
  const auto old = nlohmann::json::parse(R"({"serial": "SN1",
      "runs": {"1": {"index": 1, "orientation": "U10", "mean_g": 1e-4, "mean_y_g": 2e-4, "n": 2000,
                     "capture": "captures/run01-U10.cap", "lost": 0, "gaps": 0, "attempts": 1}},
      "in_run": {"capture": "captures/in-run-U10.cap", "n": 40000, "lost": 0, "gaps": 0, "attempts": 1}})");
  const acceptance::DutState o = acceptance::dut_state_from_json(old);
  EXPECT_EQ(o.runs.at(1).rec.mean_x, 1e-4);
  EXPECT_EQ(o.in_run->samples, 40000u);
  // Wrong types are named by their path.
  auto bad = old;
  bad["runs"]["1"]["n"] = -5;
  try {
    acceptance::dut_state_from_json(bad);
    ADD_FAILURE() << "a negative count was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("state.runs.1.n: expected a count >= 0, found -5"), std::string::npos)
        << e.what();
  }
}

TEST(Executive, APhaseSetsOnlyWhatItDeclares) {
  Fixture f("scope");
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<Phase> phases{{"a", "a", 1, [](PhaseContext& c) { c.values.set("va", 1.0); }, {{"va", "g", ""}}},
                            {"b", "b", 1, [](PhaseContext& c) { c.values.set("va", 2.0); }, {{"vb", "g", ""}}}};
  MeasurementSet v;
  declare(phases, v);
  NoPhaseState st;
  const auto r = ex.run(power_on, phases, v, st, CancelToken{}, false, {});
  EXPECT_EQ(r.outcome, RunOutcome::Error);
  EXPECT_NE(r.message.find("phase 'b' sets 'va', which it does not declare"), std::string::npos) << r.message;
  EXPECT_EQ(*v.find("va")->value, 1.0);
}

// The progress line (not a terminal: a CI log's quarter marks) says whose its percentages are:
// the bar the phase's, `run` the whole run's share of its planned device time (a review: 48 % of
// phase 7 read as the run's).
TEST(TerminalView, TheProgressLineSaysThePhasesShareAndTheRuns) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    rig::TerminalView v(f);
    std::vector<rig::Phase> phases = {{"a", "first", 300, {}}, {"b", "second", 600, {}}, {"c", "third", 100, {}}};
    v.plan(phases);
    v.phase_started(1, 3, "b", "second", 600);
    v.phase_progress(0.5, 0);
  }
  std::rewind(f);
  std::string out;
  for (int c; (c = std::fgetc(f)) != EOF;) out += static_cast<char>(c);
  std::fclose(f);
  // 300 s done and half of 600 of 1000 planned: the run 60 %, the phase 50 %, 400 s left.
  EXPECT_NE(out.find("] phase 2/3  50%  run  60%  ETA device 00:06:40"), std::string::npos) << out;
}
