// The executive against the in-process emulated plant: phases, checkpoints,
// resume, abort with the safe-state sequence, faults, and gap handling.
#include <unistd.h>

#include <filesystem>
#include <sstream>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "plant/emulated/world.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/record.hpp"
#include "rig/core/errors.hpp"
#include "rig/executive/executive.hpp"

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

}  // namespace

TEST(Executive, RunsPhasesInOrderAndCheckpointsEach) {
  Fixture f("order");
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  std::vector<std::string> ran;
  std::vector<Phase> phases;
  for (const char* id : {"a", "b", "c"})
    phases.push_back({id, id, 1.0, [&ran, id](PhaseContext& c) {
                        ran.push_back(id);
                        c.values.set(std::string("v_") + id, 1.0);
                        c.dev.clock.sleep_for(1.0, c.cancel);
                      }});
  MeasurementSet v;
  nlohmann::json state = nlohmann::json::object();
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
      {"first", "first", 1, [](PhaseContext& c) { c.values.set("kept", 42.0); }},
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
  nlohmann::json state = nlohmann::json::object();
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
  EXPECT_FALSE(f.world->io().dut_power());
}

TEST(Executive, ResumeSkipsCompletedPhasesAndRestoresState) {
  Fixture f("resume");
  int runs_a = 0, runs_b = 0;
  std::vector<Phase> phases{{"a", "a", 1,
                             [&](PhaseContext& c) {
                               ++runs_a;
                               c.state["from_a"] = 5;
                               c.values.set("va", 1.5);
                             }},
                            {"b", "b", 1, [&](PhaseContext&) {
                               ++runs_b;
                               throw HardwareError("link died");
                             }}};
  const nlohmann::json id{{"profile", "x"}};
  {
    Devices d = f.dev();
    Executive ex(d, f.out, f.log, nullptr);
    MeasurementSet v;
    nlohmann::json st = nlohmann::json::object();
    const auto r = ex.run(power_on, phases, v, st, CancelToken{}, false, id);
    EXPECT_EQ(r.outcome, RunOutcome::Error);
    EXPECT_EQ(r.exit_code(), kExitHardware);
  }
  phases[1].run = [&](PhaseContext& c) {
    ++runs_b;
    EXPECT_EQ(c.state["from_a"], 5);
  };
  Devices d = f.dev();
  Executive ex(d, f.out, f.log, nullptr);
  MeasurementSet v;
  nlohmann::json st = nlohmann::json::object();
  const auto r = ex.run(power_on, phases, v, st, CancelToken{}, true, id);
  EXPECT_EQ(r.outcome, RunOutcome::Pass);
  EXPECT_EQ(runs_a, 1) << "a completed phase is never repeated";
  EXPECT_EQ(runs_b, 2);
  EXPECT_EQ(r.phases[0].status, "skipped");
  EXPECT_EQ(*v.find("va")->value, 1.5);
  // A different identity refuses to resume.
  MeasurementSet v2;
  EXPECT_THROW(ex.run(power_on, phases, v2, st, CancelToken{}, true, {{"profile", "other"}}), ConfigError);
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
  nlohmann::json st = nlohmann::json::object();
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
  nlohmann::json st = nlohmann::json::object();
  const auto r = ex.run([&](PhaseContext& c) { acceptance::bring_up(c, prof, ro); }, {}, v, st, CancelToken{}, false, {});
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
    nlohmann::json st = nlohmann::json::object();
    PhaseContext c{d, CancelToken{}, v, st, f.out, f.log, nullptr};
    power_on(c);
    // Two seconds into the first attempt, five samples never arrive; the retry is clean.
    auto* w = f.world.get();
    w->at(c.dev.clock.now_s() + prof.settle_s + 2.0, [w] { w->inject_drop(w->next_seq() + 10, 5); });
    const auto r = acceptance::position_and_record(c, prof, Orientation::U10, 5.0, "g");
    EXPECT_EQ(r.attempts, 2);
    EXPECT_EQ(r.lost, 0u);
    EXPECT_TRUE(fs::exists(f.out + "/captures/g.cap.interrupted-1")) << "the failed attempt's capture is kept";
  }
  {
    Fixture f("gap-fail");
    Devices d = f.dev();
    for (uint32_t s = 0; s < 100000; s += 1000) f.world->inject_drop(s + 500, 2);  // every attempt loses samples
    MeasurementSet v;
    nlohmann::json st = nlohmann::json::object();
    PhaseContext c{d, CancelToken{}, v, st, f.out, f.log, nullptr};
    power_on(c);
    try {
      acceptance::position_and_record(c, prof, Orientation::U10, 5.0, "g");
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
    nlohmann::json st = nlohmann::json::object();
    PhaseContext c{d, CancelToken{}, v, st, f.out, f.log, nullptr};
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
