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
#include "plant/table/table_emulator.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/modbus/table_client.hpp"

namespace fs = std::filesystem;
using namespace rig;

// The plan's default timing is the emulated drive's power-on profile and the table client's own
// (rig/core/table.hpp's table_defaults, which all three take: procedures/ includes neither).
TEST(Plan, DefaultTableTimingIsTheEmulatedDrivesAndTheClients) {
  const acceptance::TableTiming plan;
  const plant::TableParams drive;
  const modbus::TableOptions client;
  EXPECT_EQ(plan.velocity_dps, drive.velocity_dps);
  EXPECT_EQ(plan.accel_dps2, drive.accel_dps2);
  EXPECT_EQ(plan.drive_settle_s, drive.settle_s);
  EXPECT_EQ(plan.settle_s, client.settle_s);
  EXPECT_EQ(plan.poll_s, client.poll_s);
  // What [plant.table] and the hardware file's [table] read when they set nothing.
  const plant::TableParams read_drive = plant::table_params_from_toml(nullptr);
  EXPECT_EQ(plan.velocity_dps, read_drive.velocity_dps);
  EXPECT_EQ(plan.accel_dps2, read_drive.accel_dps2);
  EXPECT_EQ(plan.drive_settle_s, read_drive.settle_s);
  const modbus::TableOptions read_client = modbus::table_options_from_toml(toml::table{});
  EXPECT_EQ(plan.settle_s, read_client.settle_s);
  EXPECT_EQ(plan.poll_s, read_client.poll_s);
}

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
  PhaseContext ctx{dev, CancelToken{}, values, out, log, nullptr, {}};
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

// A DUT that cannot run the loop test (its firmware says so, or it has no command channel) has
// the loop phase planned at no device time, and the phase takes none: the plan said 2 s or more.
TEST(Plan, ALoopTestTheDutCannotRunIsPlannedAtNoTime) {
  std::string source;
  const toml::table profile_table = acceptance::load_profile_table("ci", source);
  const acceptance::Profile p = acceptance::parse_profile(profile_table, source);
  acceptance::ProcedureState state(p);
  auto loop_planned = [&](const acceptance::DutAbilities& can) {
    for (const Phase& ph : acceptance::build_phases(p, state, {}, can))
      if (ph.id == "loop") return ph.planned_s;
    ADD_FAILURE() << "no loop phase";
    return -1.0;
  };
  EXPECT_GT(loop_planned({}), 1.0);
  EXPECT_EQ(loop_planned({.commands = true, .loop_test = false}), 0.0);
  EXPECT_EQ(loop_planned({.commands = false, .loop_test = true}), 0.0);
  auto loop_title = [&](const acceptance::DutAbilities& can) {
    for (const Phase& ph : acceptance::build_phases(p, state, {}, can))
      if (ph.id == "loop") return ph.title;
    return std::string();
  };
  EXPECT_EQ(loop_title({}), "loop test on the DUT: 5 step(s) of 1 g inside its loop, recorded");
  EXPECT_EQ(loop_title({.commands = true, .loop_test = false}), "loop test: not run (the DUT's firmware has none)")
      << "no steps where none are taken";
  EXPECT_EQ(loop_title({.commands = false, .loop_test = true}), "loop test: not run (the DUT has no command channel)");
  for (const Phase& ph : acceptance::build_phases(p, state, {}, {.commands = false, .loop_test = true}))
    if (ph.id == "loop-figures") {
      EXPECT_EQ(ph.title, "closed-loop bandwidth and settling time: not measured (no loop test, no [dut.design]): null");
    }

  // On the emulated plant whose firmware does not run it: the phase takes no device time (its
  // "no", one reply).
  toml::table plant_cfg = plant::plant_section(profile_table);
  toml::table firmware;
  firmware.insert("loop_test", false);
  plant_cfg.insert_or_assign("firmware", firmware);
  plant::EmulatedPlant world(plant_cfg);
  Devices dev{world.table(), world.dut(), world.io(), world.clock(), "emulated"};
  std::ostringstream logtext;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::ostream_sink_mt>(logtext));
  const auto phases = acceptance::build_phases(p, state, {}, {.commands = true, .loop_test = false});
  MeasurementSet values;
  acceptance::declare_values(p, phases, values);
  const std::string out = fs::temp_directory_path() / ("rigplan-noloop-" + std::to_string(::getpid()));
  fs::remove_all(out);
  fs::create_directories(out);
  PhaseContext ctx{dev, CancelToken{}, values, out, log, nullptr, {}};
  acceptance::bring_up(ctx, p, {}, state.slot());
  for (const Phase& ph : phases)
    if (ph.id == "loop") {
      const double t0 = dev.clock.now_s();
      ph.run(ctx);
      EXPECT_NEAR(dev.clock.now_s() - t0, ph.planned_s, 0.01);  // the firmware's "no" is one reply
      ASSERT_TRUE(state.slot().loop_test.has_value());
      EXPECT_FALSE(state.slot().loop_test->supported);
    }
  fs::remove_all(out);
}
