// The `loop` phase against the emulated DUT: the paper profile's measured bandwidth and settling
// time agree with the design model's figures for the same parameters within their stated
// intervals; a hardware file's `[dut] loop_test = false` leaves both null with the reason.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "firmware_link/connect.hpp"
#include "plant/dut/loop_figures.hpp"
#include "plant/emulated/plant_config.hpp"
#include "plant/emulated/world.hpp"
#include "plant/firmware/inprocess_dut.hpp"
#include "procedures/acceptance/loop_phase.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "tests/core/idle_table.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/line_rig_io.hpp"

namespace fs = std::filesystem;
using namespace rig;

namespace {

std::shared_ptr<spdlog::logger> quiet_log(std::ostringstream& os) {
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(os));
  log->set_pattern("%l %v");
  return log;
}

std::string fresh_dir(const std::string& name) {
  const std::string out = fs::temp_directory_path() / ("rigloop-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(out);
  fs::create_directories(out);
  return out;
}

const Phase& loop_phase(const std::vector<Phase>& phases) {
  for (const Phase& p : phases)
    if (p.id == "loop") return p;
  throw std::runtime_error("no loop phase");
}

using test::IdleTable;

}  // namespace

TEST(LoopPhase, PaperRunMeasuresTheModelFiguresWithinTheStatedIntervals) {
  std::string source;
  const toml::table profile_table = acceptance::load_profile_table("paper", source);
  const acceptance::Profile p = acceptance::parse_profile(profile_table, source);
  const toml::table& plant_cfg = plant::plant_section(profile_table);
  plant::EmulatedPlant world(plant_cfg);
  Devices dev{world.table(), world.dut(), world.io(), world.clock(), "emulated"};
  std::ostringstream logtext;
  acceptance::ProcedureState state(p);
  const auto phases = acceptance::build_phases(p, state);
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  const std::string out = fresh_dir("paper");
  PhaseContext ctx{dev, CancelToken{}, values, out, quiet_log(logtext), nullptr};
  acceptance::bring_up(ctx, p, {}, state.slot());  // powers the DUT and sets the profile's output filter
  loop_phase(phases).run(ctx);
  const nlohmann::json loop = state.slot().loop.value_or(nlohmann::json());

  // The design model for the same parameters and filter.
  const design::LoopFigures model = plant::loop_figures(cfg::get_table(plant_cfg, "dut"), p.filter);
  const Measurement* bw = values.find("bandwidth_0p5");
  const Measurement* ts = values.find("settling_time");
  ASSERT_TRUE(bw && bw->value && bw->lo && bw->hi) << logtext.str();
  ASSERT_TRUE(ts && ts->value && ts->lo && ts->hi);
  EXPECT_LE(*bw->lo, model.bandwidth_0p5_hz);
  EXPECT_GE(*bw->hi, model.bandwidth_0p5_hz);
  EXPECT_LE(*ts->lo, model.settling_time_s);
  EXPECT_GE(*ts->hi, model.settling_time_s);
  EXPECT_LT(*bw->hi - *bw->lo, 0.02 * *bw->value) << "an interval that means something";
  EXPECT_LT(*ts->hi - *ts->lo, 0.25 * *ts->value);
  EXPECT_EQ(bw->reason.rfind("measured on the DUT (loop test, 5 steps of 1 g)", 0), 0u) << bw->reason;
  EXPECT_EQ(ts->reason.rfind("measured on the DUT (loop test, 5 steps of 1 g)", 0), 0u) << ts->reason;

  // The raw records are in the run folder, named as the docs say.
  std::ifstream csv(out + "/" + acceptance::kLoopTestFile);
  ASSERT_TRUE(csv) << "no " << acceptance::kLoopTestFile;
  std::size_t lines = 0;
  for (std::string l; std::getline(csv, l);) lines += !l.empty() && l[0] != '#';
  EXPECT_EQ(lines, 1 + 5 * 1000u) << "a header and 5 steps of 100 ms at 10 kHz";
  EXPECT_EQ(loop["file"], acceptance::kLoopTestFile);
  EXPECT_EQ(loop["step"]["y"].size(), 900u) << "the mean normalised step after the step";
  fs::remove_all(out);
}

// A hardware-style DUT: the real CanDutLink with the options a hardware file's [dut] section
// gives (`loop_test = false`), in front of the emulated firmware, which does have a loop test.
TEST(LoopPhase, HardwareFileWithTheLoopTestOffGivesNullWithTheReason) {
  const acceptance::Profile p = acceptance::load_profile("paper");
  const toml::table dut_section = cfg::parse_string("can = \"can0\"\nloop_test = false\n", "line2.toml");
  auto src = plant::make_dut_source(nullptr, 3);
  SimClock clock;
  link::InProcessDutOptions o;
  o.link = link::link_options(dut_section);
  auto dut = link::make_inprocess_dut(*src, clock, o);
  clock.set_advance([&](double dt) { dut->step(dt); });
  IdleTable table;
  gpio::LineRigIo io(std::make_unique<gpio::SimLines>());
  Devices dev{table, *dut, io, clock, "hardware"};
  std::ostringstream logtext;
  acceptance::ProcedureState state(p);
  const auto phases = acceptance::build_phases(p, state);
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  const std::string out = fresh_dir("off");
  PhaseContext ctx{dev, CancelToken{}, values, out, quiet_log(logtext), nullptr};
  acceptance::bring_up(ctx, p, {}, state.slot());
  loop_phase(phases).run(ctx);
  values.judge_all(true);  // the paper profile limits both: null is FAIL, said once
  for (const char* name : {"bandwidth_0p5", "settling_time"}) {
    const Measurement* m = values.find(name);
    ASSERT_NE(m, nullptr);
    EXPECT_FALSE(m->value) << name << " must not come from anywhere else";
    EXPECT_EQ(m->outcome, Outcome::Fail) << name;
    EXPECT_EQ(m->verdict, "required value not measured") << name;
    EXPECT_EQ(m->reason.find("not measured"), std::string::npos) << "said once, by the verdict: " << m->reason;
    EXPECT_NE(m->reason.find("[dut] loop_test = false"), std::string::npos) << m->reason;
  }
  EXPECT_FALSE(fs::exists(out + "/" + acceptance::kLoopTestFile));
  EXPECT_EQ(dut->firmware().stats().loop_tests, 0u);
  // The passport's "skipped" names the step, as --dry-run's plan does.
  ASSERT_TRUE(state.slot().dut.has_value());
  ASSERT_EQ(state.slot().dut->skipped.size(), 1u);
  EXPECT_EQ(state.slot().dut->skipped[0].step, "loop test");
  EXPECT_NE(state.slot().dut->skipped[0].reason.find("[dut] loop_test = false"), std::string::npos)
      << state.slot().dut->skipped[0].reason;
  fs::remove_all(out);
}
