// The phases' planned device time (the `rig run --dry-run` estimate, the progress ETA) against
// the device time each phase takes on the emulated plant: the ci profile, phase by phase, as
// the executive runs them after bring-up.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "plant/emulated/plant_config.hpp"
#include "plant/emulated/world.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/toml_util.hpp"

namespace fs = std::filesystem;
using namespace rig;

TEST(Plan, EachDevicePhaseTakesItsPlannedDeviceTime) {
  std::string source;
  const toml::table profile_table = acceptance::load_profile_table("ci", source);
  const acceptance::Profile p = acceptance::parse_profile(profile_table, source);
  plant::EmulatedPlant world(plant::plant_section(profile_table));
  Devices dev{world.table(), world.dut(), world.io(), world.clock(), "emulated"};
  std::ostringstream logtext;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
  acceptance::ProcedureState state(p);
  const auto phases = acceptance::build_phases(p, state);
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  const std::string out = fs::temp_directory_path() / ("rigplan-" + std::to_string(::getpid()));
  fs::remove_all(out);
  fs::create_directories(out);
  PhaseContext ctx{dev, CancelToken{}, values, out, log, nullptr};
  acceptance::bring_up(ctx, p, {}, state.slot());
  double planned = 0, took = 0;
  for (const Phase& ph : phases) {
    const double t0 = dev.clock.now_s();
    ph.run(ctx);
    const double dt = dev.clock.now_s() - t0;
    std::printf("%-10s planned %7.3f s, took %7.3f s\n", ph.id.c_str(), ph.planned_s, dt);
    // Per phase: the table's 180 deg move (6.5 s trapezoid, settle times, a poll) and the loop
    // test's burst are modelled; the servo's lag into the in-position window is not (one or two
    // polls: measured 0.05 or 0.10 s per move).
    EXPECT_NEAR(dt, ph.planned_s, 0.15) << ph.id;
    if (ph.planned_s == 0) {
      EXPECT_EQ(dt, 0.0) << ph.id << " computes from captures: no device time";
    }
    planned += ph.planned_s;
    took += dt;
  }
  // The whole plan within 1.5 s of the phases' device time (the bring-up, DUT power-up and
  // homing from the table's start angle, is not a phase).
  EXPECT_NEAR(took, planned, 1.5);
  fs::remove_all(out);
}
