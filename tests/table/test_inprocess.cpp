// The rig's TableClient over the emulated drive in this process, in simulated
// time: the path `rig run --plant emulated` takes.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <thread>

#include "helpers.hpp"
#include "rig/core/clock.hpp"
#include "plant/table/table_emulator.hpp"
#include "rig/modbus/motion_text.hpp"
#include "rig/modbus/stop_latch.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

struct SimRig {
  explicit SimRig(const std::string& cfg = "start_angle_deg = 30.0\n", uint64_t seed = 3)
      : emu(emulator(cfg, seed)),
        clock([this](double dt) {
          emu->step(dt);
          if (on_step) on_step();
        }),
        table(m::make_inprocess_table(*emu, clock)) {}
  std::function<void()> on_step;  // runs after every step of drive time
  std::unique_ptr<plant::TableEmulator> emu;
  SimClock clock;
  std::unique_ptr<RotaryTable> table;
};

template <class F>
std::string hardware_error(F f) {
  try {
    f();
  } catch (const HardwareError& e) {
    return e.what();
  }
  return "(no HardwareError)";
}

// A party between the client and the emulated rig-v1 drive (a drive that behaves otherwise,
// another master acting at a given moment): forwards every request; a test overrides `write`
// (the words that reach the drive) and `status` (STATUS as the client reads it).
struct Between : m::RegisterDevice {
  plant::TableEmulator& emu;
  explicit Between(plant::TableEmulator& e) : emu(e) {}
  virtual void status(uint16_t&) {}
  uint8_t write_registers(uint16_t addr, const uint16_t* v, uint16_t n) override { return emu.write_registers(addr, v, n); }
  uint8_t read_registers(uint16_t addr, uint16_t n, uint16_t* out) override {
    const uint8_t rc = emu.read_registers(addr, n, out);
    if (rc == 0 && addr <= m::reg::kStatus && m::reg::kStatus < addr + n) status(out[m::reg::kStatus - addr]);
    return rc;
  }
  bool answering() const override { return emu.answering(); }
};

TEST(TableInProcess, HomeThenMove180TakesSimulatedSecondsNotWallTime) {
  SimRig r;
  const auto wall0 = std::chrono::steady_clock::now();
  r.table->home({});
  const double t_home = r.clock.now_s();
  EXPECT_GT(t_home, 1.5);  // 30° at 20°/s
  r.table->move_to(180.0, {});
  const double t_move = r.clock.now_s() - t_home;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  // 6.5 s profile + servo settling + drive settle 0.1 s + client settle 0.5 s.
  EXPECT_GT(t_move, 7.0);
  EXPECT_LT(t_move, 9.0);
  EXPECT_LT(wall, t_move / 2);  // far faster than real time even unoptimised
  const TableStatus s = r.table->status();
  EXPECT_TRUE(s.homed);
  EXPECT_TRUE(s.in_position);
  EXPECT_FALSE(s.moving);
  EXPECT_NEAR(s.actual_deg, 180.0, 0.01);
  EXPECT_NEAR(r.emu->actual_angle_deg(), 180.0, 0.005);  // the DUT feels 180° ± repeatability
  r.table->move_to(0.0, {});
  EXPECT_NEAR(r.table->status().actual_deg, 0.0, 0.01);
}

TEST(TableInProcess, MoveBeforeHomingIsRefusedClearly) {
  SimRig r;
  const std::string err = hardware_error([&] { r.table->move_to(90.0, {}); });
  EXPECT_NE(err.find("move to 90.0000°: table not homed"), std::string::npos) << err;
  EXPECT_NE(err.find("; nothing sent"), std::string::npos) << err;
  EXPECT_FALSE(r.emu->snapshot().moving);
  // Refused before anything was written: the drive is not powered, no HALT was set (a review:
  // the refusal came after servo-on and left CONTROL at servo on + HALT).
  EXPECT_FALSE(r.emu->snapshot().servo_on);
  EXPECT_FALSE(r.table->status().servo_on);
}

// An open interlock or a pressed e-stop before a move: refused with the remedy, as the alarms
// carry theirs (a technician's review: "interlock open at 0.0000°" alone).
TEST(TableInProcess, AnOpenInterlockOrAPressedEstopSaysWhatToDo) {
  SimRig r;
  r.table->home({});
  r.emu->set_interlock(false);
  std::string err = hardware_error([&] { r.table->move_to(90.0, {}); });
  EXPECT_NE(err.find("move to 90.0000°: interlock open at "), std::string::npos) << err;
  EXPECT_NE(err.find("(close the table's guard or door, then try again)"), std::string::npos) << err;
  EXPECT_FALSE(r.emu->snapshot().moving);
}

TEST(TableInProcess, AlarmMidMoveIsReportedByCodeMeaningAndAngle) {
  SimRig r("start_angle_deg = 0.0\nfault = \"following_error\"\nfault_on_move = 2\nfault_at = 0.5\n");
  r.table->home({});
  r.table->move_to(10.0, {});  // move 1 is clean
  const std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
  EXPECT_NE(err.find("move to 180.0000°: alarm 0x0021 following error at 9"), std::string::npos) << err;
  EXPECT_NE(err.find("rig table reset"), std::string::npos) << err;
  const auto s = r.emu->snapshot();
  EXPECT_FALSE(s.servo_on);
  EXPECT_FALSE(s.moving);
  // The client does not reset a following error on its own: the next move fails too.
  const std::string again = hardware_error([&] { r.table->move_to(0.0, {}); });
  EXPECT_NE(again.find("alarm 0x0021"), std::string::npos) << again;
  // A technician's reset clears it, and the table can be homed and moved again.
  auto* client = dynamic_cast<m::TableClient*>(r.table.get());
  ASSERT_NE(client, nullptr);
  client->reset_alarm({});
  r.table->home({});
  r.table->move_to(45.0, {});
  EXPECT_NEAR(r.table->status().actual_deg, 45.0, 0.01);
}

TEST(TableInProcess, DriveFaultAndOverTravelMidMove) {
  for (auto [fault, code] : {std::pair{SimFault::kDriveFault, std::string("alarm 0x0040 drive fault")},
                             std::pair{SimFault::kOverTravel, std::string("alarm 0x0030 over-travel, positive")}}) {
    SimRig r("start_angle_deg = 0.0\n");
    r.table->home({});
    r.emu->inject(fault, 0.3);
    const std::string err = hardware_error([&] { r.table->move_to(100.0, {}); });
    EXPECT_NE(err.find("move to 100.0000°: " + code), std::string::npos) << err;
    EXPECT_FALSE(r.emu->snapshot().moving);
    EXPECT_FALSE(r.emu->snapshot().servo_on);
  }
}

TEST(TableInProcess, NoAnswerMidMoveIsALinkFailureAndBounded) {
  SimRig r("start_angle_deg = 0.0\n");
  r.table->home({});
  r.emu->inject(SimFault::kNoAnswer, 0.5);
  const double t0 = r.clock.now_s();
  const std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
  EXPECT_NE(err.find("move to 180.0000°: link failure (last seen at"), std::string::npos) << err;
  EXPECT_NE(err.find("timeout"), std::string::npos) << err;
  // Failed after the profile's half way point plus the response timeouts, not the move timeout.
  EXPECT_LT(r.clock.now_s() - t0, 5.0);
  auto* client = dynamic_cast<m::TableClient*>(r.table.get());
  EXPECT_NE(client->last_stop_error().find("stop not confirmed (unanswered in time"), std::string::npos);
  // The exit-4 message itself says the halt went out unanswered (issue 13 item 8): a drive that
  // hangs takes it when it runs again (a bring-up review).
  EXPECT_NE(err.find("; stop not confirmed (unanswered in time: the drive may still take it when it answers again; the table may still be moving)"), std::string::npos) << err;
}

TEST(TableInProcess, FaultMessageSaysTheHaltWasDelivered) {
  SimRig r("start_angle_deg = 0.0\n");
  r.table->home({});
  r.emu->inject(SimFault::kOverTravel, 0.5);
  const std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
  EXPECT_NE(err.find("; halt delivered to the drive"), std::string::npos) << err;
}

// A drive answering with another register map version is refused, not misread.
class OtherMapVersion final : public m::RegisterDevice {
 public:
  explicit OtherMapVersion(m::RegisterDevice& d) : d_(d) {}
  uint8_t read_registers(uint16_t a, uint16_t n, uint16_t* out) override {
    const uint8_t rc = d_.read_registers(a, n, out);
    if (rc == 0 && m::reg::kMapVersion >= a && m::reg::kMapVersion < a + n) out[m::reg::kMapVersion - a] = 2;
    return rc;
  }
  uint8_t write_registers(uint16_t a, const uint16_t* v, uint16_t n) override { return d_.write_registers(a, v, n); }
  bool answering() const override { return true; }

 private:
  m::RegisterDevice& d_;
};

TEST(TableInProcess, MapVersionTwoIsRefused) {
  SimRig r("start_angle_deg = 0.0\n");
  OtherMapVersion v2(*r.emu);
  auto t = m::make_inprocess_table(v2, r.clock);
  const std::string e1 = hardware_error([&] { t->status(); });
  EXPECT_NE(e1.find("MAP_VERSION (register 3) reads 2"), std::string::npos) << e1;
  const std::string e2 = hardware_error([&] { t->home({}); });
  EXPECT_NE(e2.find("MAP_VERSION"), std::string::npos) << e2;
  EXPECT_FALSE(r.emu->snapshot().homing);
}

TEST(TableInProcess, CancelMidMoveStopsTheTableAndThrowsAborted) {
  SimRig r("start_angle_deg = 0.0\n");
  r.table->home({});
  CancelSource cs;
  // Trip the cancel from "the executive" when the world reaches 2 s into the move.
  const double t_start = r.clock.now_s();
  r.clock.set_advance([&](double dt) {
    r.emu->step(dt);
    if (r.clock.now_s() - t_start > 2.0) cs.request("operator pressed Ctrl-C");
  });
  EXPECT_THROW(r.table->move_to(180.0, cs.token()), AbortedError);
  for (int i = 0; i < 300; ++i) r.emu->step(0.01);
  const auto s = r.emu->snapshot();
  EXPECT_FALSE(s.moving);
  EXPECT_EQ(s.alarm_code, 0);
  EXPECT_LT(s.position_deg, 80.0);  // halted on the ramp, far from 180°
  EXPECT_GT(s.position_deg, 50.0);
}

TEST(TableInProcess, ANewMoveRightAfterACancelWaitsForRest) {
  SimRig r("start_angle_deg = 0.0\n");
  r.table->home({});
  CancelSource cs;
  const double t_start = r.clock.now_s();
  r.clock.set_advance([&](double dt) {
    r.emu->step(dt);
    if (r.clock.now_s() - t_start > 2.0) cs.request("abort");
  });
  EXPECT_THROW(r.table->move_to(180.0, cs.token()), AbortedError);
  EXPECT_TRUE(r.emu->snapshot().moving);  // still decelerating
  r.clock.set_advance([&](double dt) { r.emu->step(dt); });
  r.table->move_to(20.0, {});
  EXPECT_NEAR(r.table->status().actual_deg, 20.0, 0.01);
}

// Another master's stop or set-point mid-move ends the move at once naming it, and this client
// sends no halt over the other master's command (a review: another master's stop waited out the
// move timeout; a halt after "target register changed" ended the other master's move).
TEST(TableInProcess, AnotherMastersStopOrTargetEndsTheMoveWithoutAHaltOfOurs) {
  SimRig r("start_angle_deg = 0.0\n");
  r.table->home({});
  auto control = [&] {
    uint16_t c = 0;
    EXPECT_EQ(r.emu->read_registers(m::reg::kControl, 1, &c), 0);
    return c;
  };
  // `rig table stop` from another shell, 1 s into the move: CONTROL = servo on + HALT.
  double t_start = r.clock.now_s();
  bool sent = false;
  r.clock.set_advance([&](double dt) {
    r.emu->step(dt);
    if (!sent && r.clock.now_s() - t_start > 1.0) {
      const uint16_t halt = m::ctl::kServoOn | m::ctl::kHalt;
      sent = r.emu->write_registers(m::reg::kControl, &halt, 1) == 0;
    }
  });
  std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
  EXPECT_NE(err.find("move to 180.0000°: halted by another master (CONTROL reads 0x0101)"), std::string::npos) << err;
  EXPECT_NE(err.find("; no halt sent by this client: another master commands the table"), std::string::npos) << err;
  EXPECT_LT(r.clock.now_s() - t_start, 2.0) << "not after the move timeout";
  // Another master's target, written once the move has stopped and is settling: no halt of ours.
  r.clock.set_advance([&](double dt) { r.emu->step(dt); });
  t_start = r.clock.now_s();
  sent = false;
  r.clock.set_advance([&](double dt) {
    r.emu->step(dt);
    if (!sent && r.clock.now_s() - t_start > 1.0 && !r.emu->snapshot().moving) {
      const auto counts = static_cast<int32_t>(5.0 * m::kPosScale);
      uint16_t w[2];
      m::split_i32(counts, w);
      sent = r.emu->write_registers(m::reg::kTargetPos, w, 2) == 0;
    }
  });
  err = hardware_error([&] { r.table->move_to(10.0, {}); });
  EXPECT_TRUE(sent);
  EXPECT_NE(err.find("target register changed to 5.0000° (another Modbus master?)"), std::string::npos) << err;
  EXPECT_NE(err.find("; no halt sent by this client"), std::string::npos) << err;
  EXPECT_FALSE(control() & m::ctl::kHalt) << control();
}

// The travel limits are the drive's, in counts: an angle is judged as it will be written, and a
// refusal names it with the digits that tell it from the limit (a review: 369.99996° went to
// 370.0000° while 370.00004° was refused as "move to 370.0000°: outside [..., 370.0000°]").
TEST(TableInProcess, AnAngleIsJudgedAtTheLimitsAsTheDriveWillTakeIt) {
  SimRig r("start_angle_deg = 360.0\n");
  r.table->home({});
  for (const double deg : {369.99996, 370.00004}) {
    r.table->move_to(deg, {});
    EXPECT_NEAR(r.table->status().target_deg, 370.0, 1e-9) << deg;
  }
  for (const auto& [deg, said] : {std::pair{370.00005, "move to 370.00005°: outside the drive's travel limits "
                                                       "[-190.0000°, 370.0000°]"},
                                  std::pair{-190.00006, "move to -190.0001°: outside the drive's travel limits"},
                                  std::pair{400.0, "move to 400.0000°: outside the drive's travel limits"}}) {
    try {
      r.table->move_to(deg, {});
      ADD_FAILURE() << deg << " taken";
    } catch (const ConfigError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(said, 0), 0u) << e.what();
    }
  }
}

// Another master's CONTROL without SERVO_ON mid-move or mid-homing: the drive brakes and the table
// stays short of its goal. The call ends at once naming it, with no halt of ours (a review: the
// move waited out its timeout, 27.6 s, and said "timed out ... off target").
TEST(TableInProcess, AnotherMastersServoOffEndsTheMoveAtOnceNamingIt) {
  for (const bool homing : {false, true}) {
    SCOPED_TRACE(homing ? "home" : "move");
    SimRig r("start_angle_deg = 100.0\n");
    if (!homing) r.table->home({});
    const double t_start = r.clock.now_s();
    bool sent = false;
    r.clock.set_advance([&](double dt) {
      r.emu->step(dt);
      if (!sent && r.clock.now_s() - t_start > 1.0 && r.emu->snapshot().moving) {
        const uint16_t off = 0;
        sent = r.emu->write_registers(m::reg::kControl, &off, 1) == 0;
      }
    });
    const std::string err = hardware_error([&] {
      if (homing) r.table->home({});
      else r.table->move_to(300.0, {});
    });
    EXPECT_TRUE(sent);
    EXPECT_NE(err.find(std::string(homing ? "home" : "move to 300.0000°") +
                       ": servo switched off by another master (CONTROL reads 0x0000)"),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("; no halt sent by this client: another master commands the table"), std::string::npos) << err;
    EXPECT_LT(r.clock.now_s() - t_start, 1.5) << "at once, not after the move timeout or ended_short_s";
    uint16_t c = 0;
    EXPECT_EQ(r.emu->read_registers(m::reg::kControl, 1, &c), 0);
    EXPECT_EQ(c, 0) << std::hex << c;
  }
}

// A HALT (or QUICK_STOP) set and released again by another master between two polls, mid-move:
// the drive reads in position at its stop point, off the target. Named after [table] ended_short_s (1 s) and
// halted, as a homing run ended short is; it waited out the move timeout (31.6 s) before (a review).
// A drive whose in-position window is wider than the client's tolerance is not taken for one.
TEST(TableInProcess, AMoveStoppedShortAndReleasedIsNamedSoon) {
  for (const uint16_t stop : {m::ctl::kHalt, m::ctl::kQuickStop}) {
    SCOPED_TRACE(stop == m::ctl::kHalt ? "halt" : "quick stop");
    SimRig r("start_angle_deg = 0.0\n");
    r.table->home({});
    const double t_start = r.clock.now_s();
    int step = 0;
    r.clock.set_advance([&](double dt) {
      r.emu->step(dt);
      if (step == 0 && r.clock.now_s() - t_start > 1.0) {
        const uint16_t w = m::ctl::kServoOn | stop;
        step = r.emu->write_registers(m::reg::kControl, &w, 1) == 0 ? 1 : 0;
      } else if (step == 1) {  // on the next step, between two of the client's polls
        const uint16_t servo = m::ctl::kServoOn;
        step = r.emu->write_registers(m::reg::kControl, &servo, 1) == 0 ? 2 : 1;
      }
    });
    const std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
    EXPECT_EQ(step, 2);
    EXPECT_NE(err.find("move to 180.0000°: stopped "), std::string::npos) << err;
    EXPECT_NE(err.find(" off target, in position at that stop point for 1.0 s (halted and released by another "
                       "Modbus master?)"),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("; halt delivered to the drive"), std::string::npos) << err;
    EXPECT_LT(r.clock.now_s() - t_start, 5.0) << "not after the move timeout";
  }
  // The drive's own window wider than the client's tolerance: a good arrival reads in position
  // up to the window off the target; the client waits for its tolerance as before, not "stopped".
  SimRig r("start_angle_deg = 0.0\nin_position_window_deg = 0.5\n");
  r.table->home({});
  r.table->move_to(90.0, {});
  EXPECT_NEAR(r.table->status().actual_deg, 90.0, 0.01);
}

// Good moves on a slow, ringing servo with SETTLE_TIME 0 are not taken for moves stopped short
// (a review: 'move 10', '40', '35' each failed "stopped 1.2600° off target, in position at that
// stop point for 1.0 s" and were halted). The emulated drive read IN_POSITION off the window with
// SETTLE_TIME 0; and a drive that keeps IN_POSITION once set, until the next command, must not
// fail them either: the table still moves, so it is not at a stop point.
TEST(TableInProcess, ARingingServoIsNotAMoveStoppedShort) {
  // IN_POSITION held from the first reading that shows it until the next START or HOME.
  struct LatchedInPosition : Between {
    bool latched = false;
    using Between::Between;
    void status(uint16_t& st) override {
      latched = latched || (st & m::sts::kInPosition);
      if (latched) st = static_cast<uint16_t>(st | m::sts::kInPosition);
    }
    uint8_t write_registers(uint16_t addr, const uint16_t* v, uint16_t n) override {
      if (addr == m::reg::kControl && (v[0] & (m::ctl::kStart | m::ctl::kHome))) latched = false;
      return emu.write_registers(addr, v, n);
    }
  };
  const char* ringing =
      "start_angle_deg = 0.0\nhomed_at_start = true\nservo_bandwidth_hz = 0.3\ndamping = 0.3\n"
      "following_error_limit_deg = 90.0\nsettle_s = 0.0\n";
  for (const bool latch : {false, true}) {
    SCOPED_TRACE(latch ? "IN_POSITION latched" : "the emulated drive");
    auto emu = emulator(ringing);
    SimClock clock([&](double dt) { emu->step(dt); });
    LatchedInPosition dev(*emu);
    m::TableOptions opt;
    opt.move_timeout_s = 60.0;  // the servo takes its time: the timeout is not what is tested
    auto table = latch ? m::make_inprocess_table(dev, clock, opt) : m::make_inprocess_table(*emu, clock, opt);
    for (const double deg : {10.0, 40.0, 35.0}) {
      EXPECT_NO_THROW(table->move_to(deg, {})) << deg;
      EXPECT_NEAR(table->status().actual_deg, deg, 0.01);
    }
  }
}

// Homing is ended by another master's stop as a move is: at once, named, no halt of ours over
// it; a homing run stopped and released again (HALT set, then cleared) is named too. Both
// waited out home_timeout_s (180 s) before (session 26's safety review).
TEST(TableInProcess, AnotherMastersStopEndsHomingAtOnceNamingIt) {
  auto control = [](SimRig& r) {
    uint16_t c = 0;
    EXPECT_EQ(r.emu->read_registers(m::reg::kControl, 1, &c), 0);
    return c;
  };
  for (const bool released : {false, true}) {
    SCOPED_TRACE(released ? "halt set, then cleared" : "halt set");
    SimRig r("start_angle_deg = 200.0\n");  // 10 s of homing at 20 °/s
    const double t_start = r.clock.now_s();
    int step = 0;
    r.clock.set_advance([&](double dt) {
      r.emu->step(dt);
      const double el = r.clock.now_s() - t_start;
      if (step == 0 && el > 1.0) {
        const uint16_t halt = m::ctl::kServoOn | m::ctl::kHalt;
        step = r.emu->write_registers(m::reg::kControl, &halt, 1) == 0 ? 1 : 0;
      } else if (released && step == 1) {  // on the next step, between two of the client's polls
        const uint16_t servo = m::ctl::kServoOn;
        step = r.emu->write_registers(m::reg::kControl, &servo, 1) == 0 ? 2 : 1;
      }
    });
    const std::string err = hardware_error([&] { r.table->home({}); });
    EXPECT_EQ(step, released ? 2 : 1);
    if (released) {
      EXPECT_NE(err.find("home: homing ended without reaching the home switch (HOMED not set for 1.0"),
                std::string::npos)
          << err;
      // Halted as after any fault: a drive that only paused must not move on (a review).
      EXPECT_NE(err.find("; halt delivered to the drive"), std::string::npos) << err;
      EXPECT_EQ(control(r), m::ctl::kServoOn | m::ctl::kHalt);
    } else {
      EXPECT_NE(err.find("home: halted by another master (CONTROL reads 0x0101)"), std::string::npos) << err;
      EXPECT_NE(err.find("; no halt sent by this client: another master commands the table"), std::string::npos)
          << err;
      EXPECT_EQ(control(r), m::ctl::kServoOn | m::ctl::kHalt);  // the other master's word, not ours over it
    }
    EXPECT_LT(r.clock.now_s() - t_start, 5.0) << "not after the home timeout";
    EXPECT_FALSE(r.table->status().homed);
  }
}

// A drive that sets HOMED a while after it clears HOMING and MOVING (the map does not say they
// change in one scan) completes its home: the "ended without reaching the home switch" check
// waits [table] ended_short_s (1 s) (a review: 80 ms between them failed a good run).
TEST(TableInProcess, HomedSetLateAfterTheRunIsNotTakenForAnInterruptedHome) {
  struct LateHomed : Between {
    double lag_s, ended_at = -1;
    LateHomed(plant::TableEmulator& e, double lag) : Between(e), lag_s(lag) {}
    void status(uint16_t& st) override {
      const bool done = (st & m::sts::kHomed) && !(st & (m::sts::kHoming | m::sts::kMoving));
      if (!done) ended_at = -1;
      if (done && ended_at < 0) ended_at = emu.time_s();
      if (done && emu.time_s() - ended_at < lag_s) st = static_cast<uint16_t>(st & ~m::sts::kHomed);
    }
  };
  for (const double lag : {0.08, 0.6}) {
    SCOPED_TRACE(lag);
    auto emu = emulator("start_angle_deg = 30.0\n");
    SimClock clock([&](double dt) { emu->step(dt); });
    LateHomed late(*emu, lag);
    auto table = m::make_inprocess_table(late, clock);
    EXPECT_NO_THROW(table->home({}));
    EXPECT_TRUE(table->status().homed);
  }
}

// Another master's HALT set and released right after the drive took the HOME edge, before the
// client's first poll: the run is never seen under way. Named after [table] ended_short_s (1 s) and halted;
// it waited out home_timeout_s (180 s) before (session 27's note).
TEST(TableInProcess, AHomeStoppedBeforeTheFirstPollIsNamedSoon) {
  struct StoppedAtOnce : Between {
    bool done = false;
    using Between::Between;
    uint8_t write_registers(uint16_t addr, const uint16_t* v, uint16_t n) override {
      const uint8_t rc = emu.write_registers(addr, v, n);
      if (rc == 0 && !done && addr == m::reg::kControl && (v[0] & m::ctl::kHome)) {
        const uint16_t halt = m::ctl::kServoOn | m::ctl::kHalt, servo = m::ctl::kServoOn;
        emu.step(0.01);  // the run starts
        done = emu.write_registers(m::reg::kControl, &halt, 1) == 0;
        for (int i = 0; i < 1000 && emu.snapshot().moving; ++i) emu.step(0.001);  // at rest, still unpolled
        done = done && !emu.snapshot().moving && emu.write_registers(m::reg::kControl, &servo, 1) == 0;
      }
      return rc;
    }
  };
  auto emu = emulator("start_angle_deg = 200.0\n");
  SimClock clock([&](double dt) { emu->step(dt); });
  StoppedAtOnce dev(*emu);
  auto table = m::make_inprocess_table(dev, clock);
  const double t0 = clock.now_s();
  const std::string err = hardware_error([&] { table->home({}); });
  EXPECT_TRUE(dev.done);
  EXPECT_NE(err.find("home: homing ended without reaching the home switch (HOMED not set for 1.0 s after the "
                     "acknowledge, and the run was never seen under way; stopped by another Modbus master?)"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("; halt delivered to the drive"), std::string::npos) << err;
  EXPECT_LT(clock.now_s() - t0, 5.0) << "not after the home timeout";
}

// A homed table at 0 degrees reached through a device `Dev` (set up by `set`, then told the
// client), and a move to 180 degrees through it; `after` seconds of drive time follow the move.
struct MovedThrough {
  std::unique_ptr<plant::TableEmulator> emu;
  double at;        // where the move began
  std::string err;  // its HardwareError
};
template <class Dev, class Set>
MovedThrough move_through(Set set, double after) {
  MovedThrough o{emulator("start_angle_deg = 0.0\n"), 0, ""};
  SimClock clock([&](double dt) { o.emu->step(dt); });
  Dev dev(*o.emu);
  set(dev);
  auto table = m::make_inprocess_table(dev, clock);
  table->home({});
  o.at = o.emu->actual_angle_deg();
  dev.client = table.get();
  o.err = hardware_error([&] { table->move_to(180.0, {}); });
  clock.sleep_for(after, {});
  EXPECT_TRUE(dev.done);
  return o;
}

// A stop() from another thread (the clients allow it; the rig's own abort paths cancel the move
// instead, whose thread then stops it) that comes while a move writes its command words: the
// START word written after it cleared its HALT (CONTROL is one register), and the move ran on to
// its target with nothing halting it, the stop lost. Now no command word goes out once a stop
// has, and one that went out as the stop did is followed by the stop again. A halt and a quick
// stop, each named for what it was.
TEST(TableInProcess, AStopThatComesAsTheMoveIsStartedIsNeverWrittenOver) {
  struct StopRaces : Between {
    RotaryTable* client = nullptr;
    bool on_target = false;  // the stop as the target is written (before START), else as START is
    bool quick = false, done = false;
    using Between::Between;
    void stop() { quick ? client->quick_stop() : client->stop(); }
    uint8_t write_registers(uint16_t addr, const uint16_t* v, uint16_t n) override {
      const bool start = addr == m::reg::kControl && (v[0] & m::ctl::kStart);
      if (client && !done && (on_target ? addr == m::reg::kTargetPos : start)) {
        done = true;
        if (on_target) {
          const uint8_t rc = emu.write_registers(addr, v, n);
          stop();
          return rc;
        }
        stop();  // reaches the drive just before the START word
      }
      return emu.write_registers(addr, v, n);
    }
  };
  for (const bool quick : {false, true})
  for (const bool on_target : {true, false}) {
    SCOPED_TRACE(std::string(quick ? "quick stop" : "halt") + (on_target ? " as the target is written" : " as START is written"));
    const auto [emu, at, err] =
        move_through<StopRaces>([&](StopRaces& d) { d.on_target = on_target, d.quick = quick; }, 3.0);
    EXPECT_NE(err.find(std::string("move to 180.0000°: halted by a ") + (quick ? "quick stop" : "stop") + " request"),
              std::string::npos)
        << err;
    // The stop sent again is the kind asked: a HALT over the QUICK_STOP made the emulated drive
    // re-plan the rest of it on the slower profile ramp (22.8° of travel against 6.6°, a review).
    EXPECT_NE(err.find(std::string("; ") + (quick ? "quick stop" : "halt") + " delivered to the drive"), std::string::npos)
        << err;
    uint16_t control = 0;
    ASSERT_EQ(emu->read_registers(m::reg::kControl, 1, &control), 0);
    EXPECT_EQ((control & m::ctl::kQuickStop) != 0, quick) << std::hex << control;
    EXPECT_EQ((control & m::ctl::kHalt) != 0, !quick) << std::hex << control;
    EXPECT_NEAR(emu->actual_angle_deg(), at, 1.0) << "the move went on over the stop";
  }
}

// The latch's rules, one by one (both clients keep one). A stop still under way when an operation
// begins counts for it: its write may land after the operation's first command word (START
// clears HALT) or be read back as another master's (an outside review). One that has returned
// before does not: the operation is a later command. A quick stop is named as one.
TEST(StopLatch, CountsStopsUnderWayAtTheStartAndNamesAQuickStop) {
  using L = m::detail::StopLatch;
  L latch;
  {
    const L::Asking stopping(latch, false);  // asked, its write not yet returned
    const L::Scope op(latch, "move to 10.0000°");
    EXPECT_TRUE(latch.since_begin());
    EXPECT_EQ(latch.halted_by(), "halted by a stop request");
  }
  {
    { const L::Asking returned(latch, true); }
    const L::Scope op(latch, "move to 20.0000°");
    EXPECT_FALSE(latch.since_begin()) << "a stop that returned before the move began is superseded by it";
    EXPECT_FALSE(latch.quick_since_begin());
    { const L::Asking quick(latch, true); }
    EXPECT_TRUE(latch.since_begin());
    EXPECT_TRUE(latch.quick_since_begin());
    EXPECT_EQ(latch.halted_by(), "halted by a quick stop request");
    { const L::Asking halt(latch, false); }
    EXPECT_EQ(latch.halted_by(), "halted by a quick stop request") << "both asked: the quick stop is named";
  }
  EXPECT_FALSE(latch.since_begin()) << "no operation runs";
  {
    const L::Scope op(latch, "home");
    std::string e;
    try {
      latch.write_command(0x0003, {}, [&] { const L::Asking during(latch, true); });
    } catch (const HardwareError& x) {
      e = x.what();
    }
    EXPECT_EQ(e, "home: halted by a quick stop request that came as command word 0x0003 was written (which may have "
                 "cleared it: the stop is sent again)");
  }
}

// A halt after this client's own quick stop sends nothing: a HALT edge re-plans the rest of the
// stop on the slower profile ramp (an outside review: 22.8° of travel where the quick stop alone
// took 6.6°). The next move's command words end the quick stop's standing.
TEST(TableInProcess, AHaltNeverWeakensThisClientsQuickStop) {
  SimRig r;
  r.table->home({});
  bool started = false;
  uint16_t control = 0;
  r.on_step = [&] {
    if (started || r.emu->actual_angle_deg() < 60.0) return;
    started = true;
    r.table->quick_stop();
    r.table->stop();
    r.emu->read_registers(m::reg::kControl, 1, &control);
  };
  const std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
  r.on_step = nullptr;
  ASSERT_TRUE(started);
  EXPECT_TRUE(control & m::ctl::kQuickStop) << std::hex << control;
  EXPECT_FALSE(control & m::ctl::kHalt) << std::hex << control;
  EXPECT_NE(err.find("halted by a quick stop request"), std::string::npos) << err;
  r.clock.sleep_for(3.0, {});
  r.table->move_to(90.0, {});  // a later move is not held by it
  EXPECT_NEAR(r.emu->actual_angle_deg(), 90.0, 0.01);
  r.table->stop();
  r.emu->read_registers(m::reg::kControl, 1, &control);
  EXPECT_TRUE(control & m::ctl::kHalt) << "after a move, a halt is sent again: " << std::hex << control;
}

// A stop asked of the client that never reaches the drive (the link refuses it) after START was
// acknowledged and dropped: no command word follows, CONTROL reads no HALT, and the move went on
// and reported success (a review). And a stop asked while the move makes its first read, before
// its body began: forgotten, and the move started over it (a review). Both end the move now.
TEST(TableInProcess, AStopAskedEndsTheMoveEvenWhenItNeverReachesTheDrive) {
  struct RefusesHalt : Between {
    RotaryTable* client = nullptr;
    bool at_first_read = false;  // the stop during the move's first read, else once it moves
    bool done = false;
    using Between::Between;
    uint8_t write_registers(uint16_t addr, const uint16_t* v, uint16_t n) override {
      if (addr == m::reg::kControl && (v[0] & m::ctl::kHalt)) return 0x04;  // slave device failure
      return emu.write_registers(addr, v, n);
    }
    void status(uint16_t& st) override {
      // Once moving: 20 degrees on, well after START was acknowledged and dropped.
      if (!client || done || (!at_first_read && !((st & m::sts::kMoving) && emu.actual_angle_deg() > 20.0))) return;
      done = true;
      client->stop();
    }
  };
  for (const bool at_first_read : {false, true}) {
    SCOPED_TRACE(at_first_read ? "stop during the first read" : "stop once moving, not delivered");
    const auto [emu, at, err] = move_through<RefusesHalt>([&](RefusesHalt& d) { d.at_first_read = at_first_read; }, 0.0);
    EXPECT_NE(err.find("move to 180.0000°: halted by a stop request"), std::string::npos) << err;
    if (at_first_read) {
      EXPECT_NEAR(emu->actual_angle_deg(), at, 0.5) << "the move started over the stop";
    } else {
      EXPECT_NE(err.find("stop not delivered"), std::string::npos) << err;
      EXPECT_LT(emu->actual_angle_deg(), 170.0) << "ended at the poll after the stop, not at the target";
    }
  }
}

TEST(TableInProcess, EstopDuringMove) {
  SimRig r("start_angle_deg = 0.0\n");
  r.table->home({});
  const double t_start = r.clock.now_s();
  r.clock.set_advance([&](double dt) {
    r.emu->step(dt);
    if (r.clock.now_s() - t_start > 1.0) r.emu->set_estop(true);
  });
  const std::string err = hardware_error([&] { r.table->move_to(180.0, {}); });
  EXPECT_NE(err.find("alarm 0x0050 emergency stop"), std::string::npos) << err;
}

TEST(TableInProcess, FrozenHeartbeatMeansTheDriveIsNotRunning) {
  // A SimClock whose advance does not step the drive (a wiring mistake, or a hung controller).
  auto emu = emulator("start_angle_deg = 0.0\nhomed_at_start = true\n");
  SimClock clock;  // time moves, the drive does not
  auto table = m::make_inprocess_table(*emu, clock);
  const std::string err = hardware_error([&] { table->move_to(90.0, {}); });
  EXPECT_NE(err.find("heartbeat frozen"), std::string::npos) << err;
}

TEST(TableInProcess, MoveTimeoutHaltsTheTableAndSaysWhere) {
  auto emu = emulator("start_angle_deg = 0.0\nhomed_at_start = true\n");
  SimClock clock([&](double dt) { emu->step(dt); });
  m::TableOptions opt;
  opt.move_timeout_s = 1.0;  // a 180° move needs 6.5 s
  auto table = m::make_inprocess_table(*emu, clock, opt);
  const std::string err = hardware_error([&] { table->move_to(180.0, {}); });
  EXPECT_NE(err.find("move to 180.0000°: timed out after 1.0 s, still moving at 22.5"), std::string::npos) << err;
  for (int i = 0; i < 300; ++i) emu->step(0.01);
  EXPECT_FALSE(emu->snapshot().moving);
  EXPECT_NEAR(emu->snapshot().position_deg, 30.0, 1.0);  // halted on the ramp (22.5° + 7.5°), not carried on to 180°
}

// A drive that ignores START (e.g. a different firmware's control word): the
// client must not mistake the previous in-position for the new move's.
class IgnoresStart final : public m::RegisterDevice {
 public:
  explicit IgnoresStart(m::RegisterDevice& inner) : inner_(inner) {}
  uint8_t read_registers(uint16_t a, uint16_t n, uint16_t* out) override { return inner_.read_registers(a, n, out); }
  uint8_t write_registers(uint16_t a, const uint16_t* v, uint16_t n) override {
    std::vector<uint16_t> w(v, v + n);
    if (a == m::reg::kControl) w[0] &= static_cast<uint16_t>(~m::ctl::kStart);
    return inner_.write_registers(a, w.data(), n);
  }
  bool answering() const override { return inner_.answering(); }

 private:
  m::RegisterDevice& inner_;
};

TEST(TableInProcess, UnacknowledgedStartIsAFault) {
  auto emu = emulator("start_angle_deg = 0.0\nhomed_at_start = true\n");
  SimClock clock([&](double dt) { emu->step(dt); });
  IgnoresStart dev(*emu);
  auto table = m::make_inprocess_table(static_cast<m::RegisterDevice&>(dev), clock);
  const std::string err = hardware_error([&] { table->move_to(0.0, {}); });  // already there: in position
  EXPECT_NE(err.find("move to 0.0000°: start not acknowledged within 1.0 s"), std::string::npos) << err;
}

TEST(TableInProcess, StopAndQuickStopOnASilentDriveReturnAndSayWhy) {
  SimRig r("start_angle_deg = 0.0\n");
  auto* client = dynamic_cast<m::TableClient*>(r.table.get());
  r.table->stop();
  EXPECT_EQ(client->last_stop_error(), "");
  r.emu->inject(SimFault::kNoAnswer);
  const double t0 = r.clock.now_s();
  r.table->quick_stop();  // noexcept: a throw would terminate the test
  EXPECT_NE(client->last_stop_error().find("quick stop not confirmed (unanswered in time"), std::string::npos);
  EXPECT_NE(client->last_stop_error().find("timeout"), std::string::npos);
  // (A quick stop not confirmed does not stand: the halt after it is sent, and fails too.)
  r.table->stop();
  EXPECT_NE(client->last_stop_error().find("stop not confirmed (unanswered in time"), std::string::npos) << client->last_stop_error();
  // Bounded: one response timeout per call (urgent calls never retry in-process).
  EXPECT_NEAR(r.clock.now_s() - t0, 0.6, 1e-9);
}

}  // namespace
}  // namespace rig::table_test

namespace rig::table_test {
namespace {
// An angle that rounds to zero is "0.0000°", not "-0.0000°" (a home read back as -0.00001°
// printed so, a review); a real negative angle keeps its sign.
TEST(MotionText, AnAngleThatRoundsToZeroHasNoSign) {
  EXPECT_EQ(rig::modbus::detail::deg_str(-0.00001), "0.0000°");
  EXPECT_EQ(rig::modbus::detail::deg_str(0.0), "0.0000°");
  EXPECT_EQ(rig::modbus::detail::deg_str(-0.0001), "-0.0001°");
  EXPECT_EQ(rig::modbus::detail::deg_str(179.99996), "180.0000°");
}
}  // namespace
}  // namespace rig::table_test
