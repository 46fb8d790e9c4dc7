// The acceptance procedure builds and runs without the emulator: this executable links
// rig_acceptance and nothing from plant/ (its link closure is checked below, computed by CMake),
// and drives the loop phase through fakes of the seams. A DUT with a loop test gives figures
// with intervals from its records; one without gives null values with the reason.
#include <unistd.h>

#include <cmath>
#include <numbers>
#include <filesystem>
#include <sstream>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "design/loop_figures.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/record.hpp"
#include "tests/core/idle_table.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/capture/capture.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/gpio.hpp"
#include "rig/core/toml_util.hpp"

namespace fs = std::filesystem;
using namespace rig;

namespace {

using test::IdleTable;

// Rig I/O that is always powered and never trips (the loop phase only needs the DUT on).
class QuietIo final : public RigIo {
 public:
  void set_dut_power(bool on) override { on_ = on; }
  bool dut_power() const override { return on_; }
  bool estop_active() const override { return false; }
  void set_lamp(Lamp, bool) override {}
  void on_estop(std::function<void()>) override {}
  std::string describe() const override { return "quiet fake I/O"; }

 private:
  bool on_ = true;
};

// A DUT whose loop is first order, y[k] = a y[k-1] + (1 - a) u[k] at 10 kHz (x = y): its figures
// are known in closed form. `loop_test` false: a DUT without one (DutLink's default answer).
class FirstOrderDut final : public DutLink {
 public:
  FirstOrderDut(double a, bool has_loop_test) : a_(a), has_(has_loop_test) {}
  DutInfo info(const CancelToken&) override { return {"FAKE-1", "0.0.1", 22, 1000}; }
  void start_stream(const CancelToken&) override {}
  void stop_stream() noexcept override {}
  std::size_t read(std::span<Sample> out, const CancelToken&) override { return out.size(); }
  void set_filter(const FilterConfig& f, const CancelToken&) override { f_ = f; }
  FilterConfig get_filter(const CancelToken&) override { return f_; }
  LinkStats stats() const override { return {}; }
  void reset_stats() override {}
  std::string describe() const override { return "first-order fake DUT"; }
  LoopTestResponse loop_test(const LoopTestRequest& rq, const CancelToken& c) override {
    if (!has_) return DutLink::loop_test(rq, c);
    LoopTestResponse r{true, "", 10000, rq.amplitude_g, {}};
    const auto n = static_cast<std::size_t>(rq.record_s * r.rate_hz);
    for (int s = 0; s < rq.steps; ++s) {
      LoopStepRecord rec;
      rec.pre_samples = n / 10;
      double y = 0.25;  // an offset before the step
      for (std::size_t k = 0; k < n; ++k) {
        const double u = 0.25 + (k >= rec.pre_samples ? rq.amplitude_g : 0.0);
        y = a_ * y + (1 - a_) * u;
        rec.x.push_back(y);
        rec.y.push_back(y);
      }
      r.steps.push_back(rec);
    }
    return r;
  }

 private:
  double a_;
  bool has_;
  FilterConfig f_;
};

struct LoopRun {
  std::ostringstream logtext;
  MeasurementSet values;
  nlohmann::json state;  // the DUT's state after the phase, as analysis.json carries it
  std::string out;
  explicit LoopRun(DutLink& dut, const std::string& name) {
    out = fs::temp_directory_path() / ("rignoplant-" + std::to_string(::getpid()) + "-" + name);
    fs::create_directories(out);
    const acceptance::Profile p = acceptance::load_profile("ci");
    acceptance::ProcedureState st(p);
    const auto phases = acceptance::build_phases(p, st);
    acceptance::declare_values(p, phases, values);
    IdleTable table;
    QuietIo io;
    SimClock clock;
    Devices dev{table, dut, io, clock, "hardware"};
    auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
    PhaseContext ctx{dev, CancelToken{}, values, out, log, nullptr, {}};
    for (const Phase& ph : phases)
      if (ph.id == "loop" || ph.id == "loop-figures") ph.run(ctx);
    state = acceptance::to_json(st.slot());
  }
  ~LoopRun() { fs::remove_all(out); }
};

}  // namespace

TEST(ProcedureWithoutPlant, LinksNoEmulatorLibrary) {
  // RIG_ACCEPTANCE_CLOSURE: every library rig_acceptance links, transitively (tests/core/CMakeLists.txt).
  const std::string closure = RIG_ACCEPTANCE_CLOSURE;
  EXPECT_NE(closure.find("rig_analysis"), std::string::npos) << "the closure was computed: " << closure;
  EXPECT_EQ(closure.find("rig_plant"), std::string::npos) << closure;
}

TEST(ProcedureWithoutPlant, LoopPhaseMeasuresAFirstOrderLoopInClosedForm) {
  const double a = 0.9;
  FirstOrderDut dut(a, true);
  LoopRun r(dut, "first-order");
  const Measurement* ts = r.values.find("settling_time");
  const Measurement* bw = r.values.find("bandwidth_0p5");
  ASSERT_TRUE(ts && ts->value && bw && bw->value) << r.logtext.str();
  // Settling to 5 %: floor(ln 0.05 / ln a) periods; |H| = 0.5 where cos w = (1 + a^2 - 4 (1-a)^2) / (2a).
  EXPECT_NEAR(*ts->value, std::floor(std::log(0.05) / std::log(a)) * 1e-4, 1e-12);
  const double w = std::acos((1 + a * a - 4 * (1 - a) * (1 - a)) / (2 * a));
  EXPECT_NEAR(*bw->value, w * 10000 / (2 * std::numbers::pi), 0.05);
  // Identical steps: the interval is the resolution alone (one period; 1 Hz).
  EXPECT_NEAR(*ts->hi - *ts->lo, 1e-4, 1e-12);
  EXPECT_NEAR(*bw->hi - *bw->lo, 1.0, 1e-9);
  EXPECT_NE(ts->reason.find("measured on the DUT (loop test, 5 steps of 1 g)"), std::string::npos) << ts->reason;
  EXPECT_TRUE(fs::exists(r.out + "/" + acceptance::kLoopTestFile));
}

TEST(ProcedureWithoutPlant, ADutWithoutLoopTestLeavesBothValuesNullWithTheReason) {
  FirstOrderDut dut(0.9, false);
  LoopRun r(dut, "none");
  for (const char* name : {"bandwidth_0p5", "settling_time"}) {
    const Measurement* m = r.values.find(name);
    ASSERT_NE(m, nullptr);
    EXPECT_FALSE(m->value);
    EXPECT_EQ(m->reason, "first-order fake DUT has no loop test");
  }
  EXPECT_FALSE(fs::exists(r.out + "/" + acceptance::kLoopTestFile));
  EXPECT_EQ(r.state["loop"]["source"], "none");
}

TEST(ProcedureWithoutPlant, ALoopThatNeverFallsToHalfHasNoBandwidth) {
  FirstOrderDut dut(0.0, true);  // y = u: the amplitude response is 1 up to Nyquist
  LoopRun r(dut, "flat");
  const Measurement* bw = r.values.find("bandwidth_0p5");
  ASSERT_NE(bw, nullptr);
  EXPECT_FALSE(bw->value);
  EXPECT_NE(bw->reason.find("stays above 0.5"), std::string::npos) << bw->reason;
  EXPECT_TRUE(r.values.find("settling_time")->value) << "the settling time is still measured";
}

namespace {

// A DUT without a command channel (issue 15, 2): every command is a test failure here, since
// the procedure must not send one; the stream is all it has.
class NoCommandDut final : public DutLink {
 public:
  DutInfo info(const CancelToken&) override { return asked("info"), DutInfo{}; }
  void start_stream(const CancelToken&) override {}
  void stop_stream() noexcept override {}
  std::size_t read(std::span<Sample> out, const CancelToken&) override { return out.size(); }
  void set_filter(const FilterConfig&, const CancelToken&) override { asked("set_filter"); }
  FilterConfig get_filter(const CancelToken&) override { return asked("get_filter"), FilterConfig{}; }
  LinkStats stats() const override { return {}; }
  void reset_stats() override {}
  std::string describe() const override { return "fake DUT without commands"; }
  LoopTestResponse loop_test(const LoopTestRequest&, const CancelToken&) override {
    return {false, "no loop test: no command channel (fake)", 0, 0, {}};
  }
  DutCommandChannel command_channel() const override { return {false, "no command channel (fake)"}; }
  std::vector<std::string> asked_for;

 private:
  void asked(const char* what) { asked_for.push_back(what); }
};

struct BringUp {
  std::ostringstream logtext;
  IdleTable table;
  QuietIo io;
  SimClock clock;
  acceptance::Profile p = acceptance::load_profile("ci");
  acceptance::DutState st;
  void run(DutLink& dut, const acceptance::RunOptions& ro) {
    Devices dev{table, dut, io, clock, "hardware"};
    MeasurementSet values;
    auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
    PhaseContext ctx{dev, CancelToken{}, values, "/nonexistent", log, nullptr, {}};
    acceptance::bring_up(ctx, p, ro, st);
  }
};

}  // namespace

// A U10/U20 angle outside the travel the drive reports (a rig-v1 drive's limit registers, known
// only once it answers) ends bring-up after homing, before anything is recorded; it ended the
// run at the first U20 move, the U10 recordings spent (a review).
TEST(ProcedureWithoutPlant, BringUpRefusesAnAngleOutsideTheTravelTheDriveReports) {
  NoCommandDut dut;
  acceptance::RunOptions ro;
  ro.expected_serial = "LABEL-0412";
  BringUp inside;
  inside.table.travel = std::pair{-190.0, 370.0};
  EXPECT_NO_THROW(inside.run(dut, ro));
  BringUp outside;
  outside.table.travel = std::pair{-190.0, 100.0};
  try {
    outside.run(dut, ro);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("U20 at 180°: outside the table's travel [-190°, 100°] that idle table "
                                         "reports; nothing recorded"),
              std::string::npos)
        << e.what();
  }
  BringUp unknown;  // a client that cannot tell: nothing to check here (each move checks)
  EXPECT_NO_THROW(unknown.run(dut, ro));
}

TEST(ProcedureWithoutPlant, BringUpOfADutWithoutCommandsSkipsIdentifyAndFilterAndSaysWhy) {
  NoCommandDut dut;
  BringUp b;
  acceptance::RunOptions ro;
  ro.expected_serial = "LABEL-0412";
  b.run(dut, ro);
  EXPECT_TRUE(dut.asked_for.empty()) << dut.asked_for.front();
  ASSERT_TRUE(b.st.dut);
  EXPECT_EQ(b.st.dut->serial, "LABEL-0412");
  EXPECT_EQ(b.st.dut->firmware, "");
  EXPECT_FALSE(b.st.dut->temperature_c);
  ASSERT_EQ(b.st.dut->skipped.size(), 3u);
  EXPECT_EQ(b.st.dut->skipped[0].step, "identify");
  EXPECT_EQ(b.st.dut->skipped[1].step, "set output filter");
  EXPECT_EQ(b.st.dut->skipped[2].step, "loop test");
  for (const auto& k : b.st.dut->skipped) {
    EXPECT_NE(k.reason.find("no command channel (fake)"), std::string::npos) << k.reason;
    EXPECT_NE(b.logtext.str().find("skipped: " + k.step), std::string::npos) << b.logtext.str();
  }
  ASSERT_FALSE(b.p.filter_name.empty());
  EXPECT_NE(b.st.dut->skipped[1].reason.find("'" + b.p.filter_name + "'"), std::string::npos)
      << "names the filter not loaded: " << b.st.dut->skipped[1].reason;
  // The skipped steps survive the checkpoint's JSON form (a resume reads them back).
  const acceptance::DutState back = acceptance::dut_state_from_json(acceptance::to_json(b.st));
  ASSERT_TRUE(back.dut);
  EXPECT_EQ(back.dut->skipped.size(), 3u);
  EXPECT_EQ(back.dut->skipped[2].reason, b.st.dut->skipped[2].reason);
  EXPECT_FALSE(back.dut->temperature_c);
}

TEST(ProcedureWithoutPlant, ADutWithoutCommandsNeedsTheSerialFromTheOperator) {
  NoCommandDut dut;
  BringUp b;
  try {
    b.run(dut, {});
    FAIL() << "bring-up without --serial";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--serial"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(dut.asked_for.empty());
}

TEST(ProcedureWithoutPlant, ADutWithoutCommandsHasNullLoopFiguresWithTheReason) {
  NoCommandDut dut;
  LoopRun r(dut, "no-commands");
  for (const char* name : {"bandwidth_0p5", "settling_time"}) {
    const Measurement* m = r.values.find(name);
    ASSERT_NE(m, nullptr);
    EXPECT_FALSE(m->value);
    EXPECT_EQ(m->reason, "no loop test: no command channel (fake)");
  }
}

// Issue 15, 5: the hardware file's [dut.design] gives the loop figures of the DUT type's design
// model, labelled so, when the DUT has no loop test: design/'s figures for that loop and the
// profile's filter, never the emulator's configuration.
TEST(ProcedureWithoutPlant, ADesignModelGivesLabelledFiguresWhenTheDutHasNoLoopTest) {
  const toml::table hw = cfg::parse_string(
      "can = \"can0\"\n[design.loop]\nloop_rate_hz = 10000.0\npendulosity_kg_m = 6.5e-6\n"
      "[design.regulator]\ngain_a_per_v = 2.0e-3\n",
      "line2.toml");
  const auto model = acceptance::read_design_model(hw);
  ASSERT_TRUE(model);
  EXPECT_EQ(model->loop.pendulosity_kg_m, 6.5e-6);
  EXPECT_EQ(model->regulator.gain_a_per_v, 2.0e-3);
  EXPECT_EQ(model->source.rfind("line2.toml:", 0), 0u) << model->source;
  EXPECT_FALSE(acceptance::read_design_model(cfg::parse_string("can = \"can0\"\n", "hw.toml")));
  EXPECT_THROW(acceptance::read_design_model(cfg::parse_string("[design.loop]\nno_such = 1\n", "hw.toml")), ConfigError);

  NoCommandDut dut;  // no loop test (no command channel)
  acceptance::Profile p = acceptance::load_profile("ci");
  p.design_model = model;
  const design::LoopFigures want = design::loop_figures(model->loop, model->regulator, p.filter);
  IdleTable table;
  QuietIo io;
  SimClock clock;
  Devices dev{table, dut, io, clock, "hardware"};
  std::ostringstream logtext;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
  // The loop test and the figures' phase of profile `pr` into `values`.
  const auto run_loop_phases = [&](const acceptance::Profile& pr, acceptance::ProcedureState& st, MeasurementSet& values) {
    const auto phases = acceptance::build_phases(pr, st);
    acceptance::declare_values(pr, phases, values);
    PhaseContext ctx{dev, CancelToken{}, values, "/nonexistent", log, nullptr, {}};
    for (const Phase& ph : phases)
      if (ph.id == "loop" || ph.id == "loop-figures") ph.run(ctx);
  };
  acceptance::ProcedureState st(p);
  MeasurementSet values;
  run_loop_phases(p, st, values);
  const Measurement* bw = values.find("bandwidth_0p5");
  const Measurement* ts = values.find("settling_time");
  ASSERT_TRUE(bw && bw->value && ts && ts->value);
  EXPECT_EQ(*bw->value, want.bandwidth_0p5_hz);
  EXPECT_EQ(*ts->value, want.settling_time_s);
  EXPECT_GT(want.bandwidth_0p5_hz, 0);
  for (const Measurement* m : {bw, ts}) {
    EXPECT_EQ(m->reason.rfind("design model of the DUT type ([dut.design] at line2.toml:", 0), 0u) << m->reason;
    EXPECT_NE(m->reason.find("not measured on this DUT: no loop test"), std::string::npos) << m->reason;
    EXPECT_FALSE(m->lo) << "a model has no measured interval";
  }
  EXPECT_EQ(st.slot().loop.value()["source"], "design model");

  // A filter slower than the model's longest step: the settling time is null with why, not the
  // window's length as a figure (the step window grew for slow filters, a review).
  acceptance::Profile slow = p;
  slow.filter = design::butterworth_lowpass(1, 1e-6, model->loop.loop_rate_hz);
  acceptance::ProcedureState slow_st(slow);
  MeasurementSet slow_values;
  run_loop_phases(slow, slow_st, slow_values);
  const Measurement* slow_ts = slow_values.find("settling_time");
  ASSERT_TRUE(slow_ts);
  EXPECT_FALSE(slow_ts->value);
  EXPECT_NE(slow_ts->reason.find("; the model's step had not settled in the first half of its longest window "
                                 "(409.6 s): at least "),
            std::string::npos)
      << slow_ts->reason;
  EXPECT_TRUE(slow_st.slot().loop.value()["settling_time_s"].is_null());
  const Measurement* slow_bw = slow_values.find("bandwidth_0p5");
  ASSERT_TRUE(slow_bw && slow_bw->value);
  EXPECT_NEAR(*slow_bw->value, std::sqrt(3.0) * 1e-6, 1e-8);  // the grid follows the cut-off down
  EXPECT_EQ(slow_st.slot().loop.value()["settling_time_reason"], slow_ts->reason);

  // An unstable design model gives no figures, and says why (its NaN step read as settled).
  acceptance::Profile hot = p;
  hot.design_model->regulator.gain_a_per_v = 1000;
  acceptance::ProcedureState hot_st(hot);
  MeasurementSet hot_values;
  run_loop_phases(hot, hot_st, hot_values);
  for (const char* name : {"bandwidth_0p5", "settling_time"}) {
    const Measurement* m = hot_values.find(name);
    ASSERT_TRUE(m) << name;
    EXPECT_FALSE(m->value) << name;
    EXPECT_NE(m->reason.find("; the design model's closed loop is unstable (a pole at |z| = "), std::string::npos)
        << m->reason;
  }
}

// A capture that no longer holds what its recording wrote (a review: with the process's stderr
// closed, the progress display was written into the raw capture, and the values were computed
// from a quarter of it, PASS) is never analysed: the phase fails, naming the file and both counts.
TEST(ProcedureWithoutPlant, ACaptureChangedAfterItsRecordingIsNotAnalysed) {
  const std::string out = fs::temp_directory_path() / ("rignoplant-" + std::to_string(::getpid()) + "-changed");
  fs::create_directories(out + "/captures");
  const acceptance::Profile p = acceptance::load_profile("ci");
  acceptance::ProcedureState st(p);
  const auto phases = acceptance::build_phases(p, st);
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  const uint64_t planned = 2000;
  {
    capture::Writer w(out + "/captures/in-run-U10.cap", capture::Header{"SN", "in-run-U10", "U10", "", "g", p.rate_hz, {}});
    std::vector<Sample> s(planned / 4);
    for (std::size_t i = 0; i < s.size(); ++i) s[i].seq = static_cast<uint32_t>(i);
    w.append(s);
    w.close();
  }
  acceptance::Recorded r;
  r.capture = "captures/in-run-U10.cap";
  r.samples = planned;
  st.slot().in_run = r;
  IdleTable table;
  QuietIo io;
  SimClock clock;
  FirstOrderDut dut(0.5, true);
  Devices dev{table, dut, io, clock, "hardware"};
  std::ostringstream logtext;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
  PhaseContext ctx{dev, CancelToken{}, values, out, log, nullptr, {}};
  const auto b = std::find_if(phases.begin(), phases.end(), [](const Phase& ph) { return ph.id == "in-run-b"; });
  ASSERT_NE(b, phases.end());
  try {
    b->run(ctx);
    ADD_FAILURE() << "analysed a capture of 500 samples recorded as 2000";
  } catch (const HardwareError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("captures/in-run-U10.cap: 500 samples"), std::string::npos) << m;
    EXPECT_NE(m.find("its recording wrote 2000 samples"), std::string::npos) << m;
  }
  for (const Measurement& m : values.all()) EXPECT_FALSE(m.value) << m.name << ": no value from it";
  fs::remove_all(out);
}

namespace {

// A DUT without a command channel that streams at `hz` on the rig's clock: each read takes the
// time its samples take.
class PacedDut final : public DutLink {
 public:
  PacedDut(SimClock& clock, double hz) : clock_(clock), hz_(hz) {}
  DutInfo info(const CancelToken&) override { return {}; }
  void start_stream(const CancelToken&) override {}
  void stop_stream() noexcept override {}
  std::size_t read(std::span<Sample> out, const CancelToken& c) override {
    clock_.sleep_for(static_cast<double>(out.size()) / hz_, c);
    return out.size();
  }
  void set_filter(const FilterConfig&, const CancelToken&) override {}
  FilterConfig get_filter(const CancelToken&) override { return {}; }
  LinkStats stats() const override { return {}; }
  void reset_stats() override {}
  std::string describe() const override { return "paced fake DUT"; }
  DutCommandChannel command_channel() const override { return {false, "no command channel (fake)"}; }

 private:
  SimClock& clock_;
  double hz_;
};

}  // namespace

// A DUT that streams at another rate than the profile's (500 Hz under ci's 1000 Hz), with no
// command channel to declare its own: the recording's pace on the rig's clock says so and stops
// the run as a configuration error, instead of stamping every capture with the wrong rate (an
// integrator's review); at its rate, or 2 % off, it records.
TEST(ProcedureWithoutPlant, ADutStreamingAtAnotherRateThanTheProfilesIsFoundByItsPace) {
  const acceptance::Profile p = acceptance::load_profile("ci");
  const std::string out = fs::temp_directory_path() / ("rignoplant-" + std::to_string(::getpid()) + "-pace");
  fs::create_directories(out);
  for (const double hz : {1000.0, 980.0, 500.0}) {
    IdleTable table;
    QuietIo io;
    SimClock clock;
    PacedDut dut(clock, hz);
    Devices dev{table, dut, io, clock, "hardware"};
    MeasurementSet values;
    std::ostringstream logtext;
    auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
    PhaseContext ctx{dev, CancelToken{}, values, out, log, nullptr, {}};
    const std::string name = "in-run-U10-" + std::to_string(static_cast<int>(hz));
    if (hz != 500.0) {
      EXPECT_NO_THROW(acceptance::position_and_record(ctx, p, Orientation::U10, p.in_run_s, name, "SN"))
          << hz << " Hz";
      continue;
    }
    try {
      acceptance::position_and_record(ctx, p, Orientation::U10, p.in_run_s, name, "SN");
      ADD_FAILURE() << "a 500 Hz stream recorded as 1000 Hz";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(name + ": 40000 samples took 80 s of the rig's clock, 40 s at the "
                                           "profile's rate_hz = 1000: the DUT streams at about 500 Hz"),
                std::string::npos)
          << e.what();
    }
  }
  fs::remove_all(out);
}
