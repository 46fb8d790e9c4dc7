// Third-party Modbus masters drive the emulated CiA 402 drive through the
// state machine to a homing run and a move, using nothing but the map page
// (docs/cia402-drive-maps.md) and drives/generic-cia402.toml: mbpoll (the
// page's section 4, command for command) and a pymodbus script. This proves
// the emulator follows the documented standard, not just the rig's client.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <thread>

#include "helpers.hpp"
#include "plant/table/cia402_drive.hpp"
#include "plant/table/table_server.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

struct Served {
  Served()
      : map(m::load_drive_map(RIG_SOURCE_DIR "/drives/generic-cia402.toml")),
        axis(emulator(kFastTable)),
        drive(*axis, map),
        server(drive, [this](double dt) { drive.step(dt); }, "tcp:127.0.0.1:0") {
    server.start();
    port = server.endpoint().substr(server.endpoint().rfind(':') + 1);
  }
  m::DriveMap map;
  std::unique_ptr<plant::TableEmulator> axis;
  plant::Cia402Drive drive;
  plant::TableServer server;
  std::string port;
};

// The first value mbpoll printed ("[1]: \t0x0237" or "[5]: \t2949120").
long value(const std::string& out) {
  const auto p = out.find("]:");
  if (p == std::string::npos) return -1;
  return std::strtol(out.c_str() + p + 2, nullptr, 0);
}

TEST(Cia402ThirdParty, MbpollFollowsTheMapPage) {
  Served s;
  const std::string mb = "mbpoll -m tcp -p " + s.port + " -a 1 -0 -1 ";
  std::string out;
  auto statusword = [&] {
    EXPECT_EQ(run(mb + "-t 4:hex -r 1 127.0.0.1", out), 0) << out;
    return value(out);
  };
  auto write = [&](int reg, const std::string& v, const std::string& type = "4") {
    ASSERT_EQ(run(mb + "-t " + type + " -r " + std::to_string(reg) + " 127.0.0.1 " + v, out), 0) << out;
  };
  auto wait_for = [&](const std::function<bool(long)>& ok, const char* what) {
    for (int i = 0; i < 500; ++i) {
      if (ok(statusword())) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ADD_FAILURE() << what << ": statusword " << std::hex << statusword();
  };
  // The drive leaves Not ready to switch on by itself once its server has stepped it, and takes
  // each controlword on its next step: a master polls for the state, as the map page says.
  wait_for([](long sw) { return (sw & 0x4F) == 0x40; }, "switch on disabled");
  write(0, "6");
  wait_for([](long sw) { return (sw & 0x6F) == 0x21; }, "ready to switch on");
  write(0, "7");
  wait_for([](long sw) { return (sw & 0x6F) == 0x23; }, "switched on");
  write(0, "15");
  wait_for([](long sw) { return (sw & 0x6F) == 0x27; }, "operation enabled");
  write(3, "6");
  write(19, "19");
  write(0, "31");
  wait_for([](long sw) { return (sw & 0x1400) == 0x1400; }, "homing attained");
  write(0, "15");
  write(3, "1");
  write(9, "2949120", "4:int -B");
  write(0, "31");
  wait_for([](long sw) { return (sw & 0x1000) != 0; }, "set-point acknowledge");
  write(0, "15");
  wait_for([](long sw) { return (sw & 0x1400) == 0x0400; }, "target reached");
  ASSERT_EQ(run(mb + "-t 4:int -B -r 5 127.0.0.1", out), 0) << out;
  EXPECT_NEAR(value(out), 2949120, 330) << out;  // within 0.01°
  EXPECT_NEAR(s.axis->actual_angle_deg(), 90.0, 0.005);
}

TEST(Cia402ThirdParty, PymodbusFollowsTheMapPage) {
  Served s;
  std::string out;
  ASSERT_EQ(run("/usr/bin/python3 " RIG_SOURCE_DIR "/tests/table/cia402_pymodbus.py 127.0.0.1 " + s.port, out), 0)
      << out;
  EXPECT_NE(out.find("OK position_actual"), std::string::npos) << out;  // the script checks it is within 0.01°
  EXPECT_NEAR(s.axis->actual_angle_deg(), -45.0, 0.005);
}

}  // namespace
}  // namespace rig::table_test
