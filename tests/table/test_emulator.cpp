// The emulated drive on its own: register map, exception codes, motion model.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "helpers.hpp"
#include "rig/modbus/registers.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;
using plant::TableEmulator;

std::vector<uint16_t> rd(TableEmulator& e, uint16_t addr, uint16_t n) {
  std::vector<uint16_t> v(n);
  EXPECT_EQ(e.read_registers(addr, n, v.data()), m::exc::kNone) << "read at " << addr;
  return v;
}
uint8_t wr(TableEmulator& e, uint16_t addr, std::vector<uint16_t> v) {
  return e.write_registers(addr, v.data(), static_cast<uint16_t>(v.size()));
}
uint8_t wr_target(TableEmulator& e, double deg) {
  uint16_t w[2];
  m::split_i32(static_cast<int32_t>(std::lround(deg * m::kPosScale)), w);
  return wr(e, m::reg::kTargetPos, {w[0], w[1]});
}
// Runs until in position (or the limit), returns the simulated time taken.
double run_until_in_position(TableEmulator& e, double limit_s = 60) {
  double t = 0;
  while (t < limit_s) {
    e.step(0.01);
    t += 0.01;
    if (e.snapshot().in_position && !e.snapshot().moving) break;
  }
  return t;
}
void servo_on_and_home(TableEmulator& e) {
  ASSERT_EQ(wr(e, m::reg::kControl, {m::ctl::kServoOn}), m::exc::kNone);
  ASSERT_EQ(wr(e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kHome}), m::exc::kNone);
  for (int i = 0; i < 6000 && !e.snapshot().homed; ++i) e.step(0.01);
  ASSERT_TRUE(e.snapshot().homed);
  ASSERT_EQ(wr(e, m::reg::kControl, {m::ctl::kServoOn}), m::exc::kNone);
  run_until_in_position(e);
}

TEST(TableEmulator, IdentityAndDefaults) {
  auto e = emulator("");
  const auto r = rd(*e, 0, m::reg::kBlockEnd);
  EXPECT_EQ(r[m::reg::kMapVersion], m::reg::kMapVersionValue);
  EXPECT_EQ(m::join_u32(r[m::reg::kVelocity], r[m::reg::kVelocity + 1]), 30000u);  // 30 deg/s
  EXPECT_EQ(m::join_i32(r[m::reg::kLimitNeg], r[m::reg::kLimitNeg + 1]), -1900000);
  EXPECT_EQ(r[m::reg::kStatus] & m::sts::kHomed, 0);
  EXPECT_NE(r[m::reg::kStatus] & m::sts::kReady, 0);
  EXPECT_NE(r[m::reg::kStatus] & m::sts::kInterlockOk, 0);
}

TEST(TableEmulator, HeartbeatCountsDriveTime) {
  auto e = emulator("");
  const auto h0 = rd(*e, m::reg::kHeartbeat, 2);
  e->step(1.0);
  const auto h1 = rd(*e, m::reg::kHeartbeat, 2);
  EXPECT_EQ(m::join_u32(h1[0], h1[1]) - m::join_u32(h0[0], h0[1]), 100u);
}

TEST(TableEmulator, ExceptionCodes) {
  auto e = emulator("");
  uint16_t buf[8];
  EXPECT_EQ(e->read_registers(30, 1, buf), m::exc::kIllegalAddress);       // hole in the map
  EXPECT_EQ(e->read_registers(20, 8, buf), m::exc::kIllegalAddress);       // runs past the drive block
  EXPECT_EQ(e->read_registers(0, 0, buf), m::exc::kIllegalValue);          // quantity 0
  EXPECT_EQ(wr(*e, m::reg::kStatus, {0}), m::exc::kIllegalAddress);        // read-only
  EXPECT_EQ(wr(*e, m::reg::kTargetPos, {0}), m::exc::kIllegalAddress);     // half a 32-bit value
  EXPECT_EQ(wr(*e, m::reg::kTargetPos + 1, {0}), m::exc::kIllegalAddress);
  EXPECT_EQ(wr(*e, m::reg::kControl, {0x8000}), m::exc::kIllegalValue);    // undefined control bit
  EXPECT_EQ(wr_target(*e, 400.0), m::exc::kIllegalValue);                  // beyond the travel limit
  EXPECT_EQ(wr(*e, m::reg::kVelocity, {0, 0}), m::exc::kIllegalValue);     // zero velocity
  EXPECT_EQ(wr(*e, m::reg::kInPosWindow, {0}), m::exc::kIllegalValue);
  // A refused request changes nothing.
  EXPECT_EQ(rd(*e, m::reg::kVelocity, 2)[1], 30000u & 0xFFFF);
}

TEST(TableEmulator, BusyWhileMoving) {
  auto e = emulator(kFastTable);
  servo_on_and_home(*e);
  ASSERT_EQ(wr_target(*e, 90), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(0.05);
  ASSERT_TRUE(e->snapshot().moving);
  EXPECT_EQ(wr_target(*e, 10), m::exc::kBusy);
  EXPECT_EQ(wr(*e, m::reg::kVelocity, {0, 1000}), m::exc::kBusy);
  EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kHome}), m::exc::kBusy);
}

TEST(TableEmulator, MoveRefusedWithAlarmUntilHomed) {
  auto e = emulator("");
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn}), m::exc::kNone);
  ASSERT_EQ(wr_target(*e, 90), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(1.0);
  const auto r = rd(*e, 0, m::reg::kBlockEnd);
  EXPECT_EQ(r[m::reg::kAlarmCode], m::alarm::kNotHomed);
  EXPECT_NE(r[m::reg::kStatus] & m::sts::kAlarm, 0);
  EXPECT_EQ(r[m::reg::kStatus] & m::sts::kMoving, 0);
  EXPECT_EQ(e->snapshot().move_seq, 0);
  // A refusal is safe to reset; the servo stays on.
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kAlarmReset}), m::exc::kNone);
  EXPECT_EQ(rd(*e, m::reg::kAlarmCode, 1)[0], m::alarm::kNone);
  EXPECT_TRUE(e->snapshot().servo_on);
}

TEST(TableEmulator, HomingFindsTheSwitchAtMechanicalZero) {
  auto e = emulator("start_angle_deg = 42.0\nhome_velocity_dps = 50.0\n");
  EXPECT_NEAR(e->actual_angle_deg(), 42.0, 1e-9);
  EXPECT_NEAR(e->snapshot().position_deg, 0.0, 1e-9);  // incremental encoder: 0 at power-on
  servo_on_and_home(*e);
  EXPECT_NEAR(e->actual_angle_deg(), 0.0, 1e-3);
  EXPECT_NEAR(e->snapshot().position_deg, 0.0, 1e-3);
}

TEST(TableEmulator, TrapezoidalMoveTakesTheProfileTime) {
  // 180° at 30°/s and 60°/s²: 0.5 s ramps + 5.5 s cruise = 6.5 s, then settling.
  auto e = emulator("start_angle_deg = 0.0\nrepeatability_deg = 0.0\n");
  servo_on_and_home(*e);
  ASSERT_EQ(wr_target(*e, 180), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(3.25);  // half way in time = half way in angle (symmetric profile)
  EXPECT_NEAR(e->snapshot().reference_deg, 90.0, 1e-6);
  EXPECT_NEAR(e->snapshot().velocity_dps, 30.0, 0.01);
  e->step(3.25);
  EXPECT_NEAR(e->snapshot().reference_deg, 180.0, 1e-9);
  const double settle = run_until_in_position(*e);
  EXPECT_LT(settle, 1.0);
  EXPECT_NEAR(e->snapshot().position_deg, 180.0, 0.001);
  EXPECT_EQ(e->snapshot().move_seq, 2);  // home + start
}

TEST(TableEmulator, RepeatabilityIsSeededAndHasTheConfiguredSpread) {
  const char* cfg = "start_angle_deg = 0.0\nrepeatability_deg = 0.001\nvelocity_dps = 360.0\naccel_dps2 = 3600.0\n";
  auto run_moves = [&](uint64_t seed) {
    auto e = emulator(cfg, seed);
    servo_on_and_home(*e);
    std::vector<double> err;
    for (int i = 0; i < 200; ++i) {
      const double target = (i % 2) ? 180.0 : 0.0;
      EXPECT_EQ(wr_target(*e, target), m::exc::kNone);
      EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
      EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn}), m::exc::kNone);
      run_until_in_position(*e);
      err.push_back(e->actual_angle_deg() - target);
    }
    return err;
  };
  const auto a = run_moves(11), b = run_moves(11), c = run_moves(12);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  double s2 = 0;
  for (double x : a) s2 += x * x;
  const double sd = std::sqrt(s2 / a.size());
  EXPECT_GT(sd, 0.0008);
  EXPECT_LT(sd, 0.0012);
}

TEST(TableEmulator, FollowingErrorFaultMidMove) {
  auto e = emulator("start_angle_deg = 0.0\n");
  servo_on_and_home(*e);
  e->inject(SimFault::kFollowing, 0.5);
  ASSERT_EQ(wr_target(*e, 180), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(8.0);
  const auto s = e->snapshot();
  EXPECT_EQ(s.alarm_code, m::alarm::kFollowing);
  EXPECT_FALSE(s.servo_on);
  EXPECT_FALSE(s.moving);
  EXPECT_NEAR(s.position_deg, 90.0, 1.0);  // seized at half way
}

TEST(TableEmulator, EstopStopsAndBlocksReset) {
  auto e = emulator(kFastTable);
  servo_on_and_home(*e);
  ASSERT_EQ(wr_target(*e, 180), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(0.1);
  ASSERT_EQ(wr(*e, m::reg::kSimInputs, {1}), m::exc::kNone);  // e-stop pressed
  const double p = e->snapshot().position_deg;
  e->step(0.5);
  EXPECT_EQ(e->snapshot().alarm_code, m::alarm::kEstop);
  EXPECT_DOUBLE_EQ(e->snapshot().position_deg, p);
  EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kAlarmReset}), m::exc::kNone);
  EXPECT_EQ(e->snapshot().alarm_code, m::alarm::kEstop);  // cause still present
  ASSERT_EQ(wr(*e, m::reg::kSimInputs, {0}), m::exc::kNone);
  EXPECT_EQ(wr(*e, m::reg::kControl, {0}), m::exc::kNone);
  EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kAlarmReset}), m::exc::kNone);
  EXPECT_EQ(e->snapshot().alarm_code, m::alarm::kNone);
}

TEST(TableEmulator, CommTimeoutStopsAMoveNobodyWatches) {
  auto e = emulator("start_angle_deg = 0.0\ncomm_timeout_s = 0.5\n");
  servo_on_and_home(*e);
  ASSERT_EQ(wr_target(*e, 180), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(0.4);
  rd(*e, m::reg::kStatus, 1);  // a master still polling keeps it going
  e->step(0.4);
  EXPECT_EQ(e->snapshot().alarm_code, 0);
  e->step(0.2);
  EXPECT_EQ(e->snapshot().alarm_code, m::alarm::kCommLost);
  EXPECT_FALSE(e->snapshot().moving);
}

TEST(TableEmulator, InterlockRefusesMovesAndStopsMotion) {
  auto e = emulator(kFastTable);
  servo_on_and_home(*e);
  e->set_interlock(false);
  ASSERT_EQ(wr_target(*e, 90), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  EXPECT_EQ(e->snapshot().alarm_code, m::alarm::kNotReady);
  EXPECT_EQ(e->snapshot().status & m::sts::kInterlockOk, 0);
  e->set_interlock(true);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kAlarmReset}), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(0.1);
  e->set_interlock(false);
  EXPECT_EQ(e->snapshot().alarm_code, m::alarm::kInterlock);
  EXPECT_FALSE(e->snapshot().servo_on);
}

TEST(TableEmulator, HaltDeceleratesOnTheProfileRamp) {
  auto e = emulator("start_angle_deg = 0.0\n");
  servo_on_and_home(*e);
  ASSERT_EQ(wr_target(*e, 180), m::exc::kNone);
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  e->step(2.0);  // cruising at 30°/s, reference at 52.5°
  ASSERT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kHalt}), m::exc::kNone);
  run_until_in_position(*e);
  // Stopping distance v²/2a = 900/120 = 7.5°.
  EXPECT_NEAR(e->snapshot().position_deg, 60.0, 0.01);
  EXPECT_EQ(e->snapshot().alarm_code, 0);
}

// A stop edge never lengthens a stop under way (table-registers.md): a HALT after a QUICK_STOP,
// another master's or another `rig table` process's, keeps the quick-stop ramp (it re-planned the
// rest on the profile ramp: 22.8° of travel where the quick stop alone took 6.6°), and a quick
// stop after a halt still shortens it.
TEST(TableEmulator, AStopNeverLengthensAStopUnderWay) {
  auto stop_point = [](std::vector<uint16_t> words) {
    auto e = emulator("start_angle_deg = 0.0\n");
    servo_on_and_home(*e);
    EXPECT_EQ(wr_target(*e, 180), m::exc::kNone);
    EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
    e->step(2.0);  // cruising at 30°/s
    for (const uint16_t w : words) {
      EXPECT_EQ(wr(*e, m::reg::kControl, {w}), m::exc::kNone);
      e->step(0.01);  // the quick stop's ramp takes 0.05 s from 30°/s
    }
    run_until_in_position(*e);
    EXPECT_EQ(e->snapshot().alarm_code, 0);
    return e->snapshot().position_deg;
  };
  const uint16_t quick = m::ctl::kServoOn | m::ctl::kQuickStop, halt = m::ctl::kServoOn | m::ctl::kHalt;
  const double quick_only = stop_point({quick}), halt_only = stop_point({halt});
  ASSERT_LT(quick_only, halt_only - 1.0);  // the quick-stop ramp is the steeper here
  EXPECT_NEAR(stop_point({quick, halt}), quick_only, 1e-9);
  EXPECT_NEAR(stop_point({quick, m::ctl::kServoOn, halt}), quick_only, 1e-9);  // re-armed edge
  EXPECT_LT(stop_point({halt, quick}), halt_only - 1.0);                      // steeper taken
}

// Nor a move's own final deceleration: a QUICK_STOP whose ramp is gentler than ACCEL, arriving
// while a move decelerates onto its target, stops on the move's ramp (at the target), not on the
// gentler quick-stop ramp past it (a review: the rule covered stops under way, not a move's ramp).
TEST(TableEmulator, AQuickStopNeverLengthensAMovesOwnDeceleration) {
  auto e = emulator("start_angle_deg = 0.0\naccel_dps2 = 60.0\nquick_stop_dps2 = 10.0\n");
  servo_on_and_home(*e);
  EXPECT_EQ(wr_target(*e, 90), m::exc::kNone);
  EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kStart}), m::exc::kNone);
  // 30 deg/s at 60 deg/s^2: 0.5 s up, 2.5 s flat, 0.5 s down from 3.0 s; the quick stop lands at
  // 3.25 s, 15 deg/s and 1.875 deg short of 90. On its own 10 deg/s^2 it would take 11.25 deg.
  e->step(3.25);
  ASSERT_TRUE(e->snapshot().moving);
  ASSERT_NEAR(e->snapshot().velocity_dps, 15.0, 1.0);
  EXPECT_EQ(wr(*e, m::reg::kControl, {m::ctl::kServoOn | m::ctl::kQuickStop}), m::exc::kNone);
  run_until_in_position(*e);
  EXPECT_NEAR(e->snapshot().position_deg, 90.0, 0.05);
  EXPECT_EQ(e->snapshot().alarm_code, 0);
}

}  // namespace
}  // namespace rig::table_test
