// `rig table status|home|move|stop|quick-stop|reset` against the emulator on a
// real wire, checking output and the documented exit codes (docs/contracts.md).
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "helpers.hpp"
#include "plant/table/table_server.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

class RigTable : public ::testing::Test {
 protected:
  void SetUp() override {
    server_.start();
    where_ = "--modbus " + server_.endpoint().substr(4);
  }
  int rig(const std::string& args, std::string& out) { return run(std::string(RIG_BIN) + " table " + args, out); }
  std::unique_ptr<plant::TableEmulator> emu_ = emulator(kFastTable);
  plant::TableServer server_{*emu_, "tcp:127.0.0.1:0"};
  std::string where_;
};

TEST_F(RigTable, StatusHomeMove) {
  std::string out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find("alarm      none"), std::string::npos) << out;
  EXPECT_NE(out.find("modbus " + server_.endpoint() + " unit 1"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  EXPECT_NE(out.find("homed"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " move 123.25", out), 0) << out;
  EXPECT_NE(out.find("actual     123.2500°"), std::string::npos) << out;
  EXPECT_NE(out.find("in-position"), std::string::npos) << out;
  EXPECT_NEAR(emu_->actual_angle_deg(), 123.25, 0.005);
  ASSERT_EQ(rig(where_ + " status --json", out), 0) << out;
  EXPECT_NE(out.find("\"homed\": true"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " stop", out), 0) << out;
  ASSERT_EQ(rig(where_ + " quick-stop", out), 0) << out;
  EXPECT_NE(out.find("quick stop sent"), std::string::npos) << out;
}

TEST_F(RigTable, FaultsExitWithFourAndSayWhat) {
  std::string out;
  EXPECT_EQ(rig(where_ + " move 90", out), 4) << out;
  EXPECT_NE(out.find("move to 90.0000°: table not homed"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  emu_->inject(SimFault::kDriveFault, 0.5);
  EXPECT_EQ(rig(where_ + " move 180", out), 4) << out;
  EXPECT_NE(out.find("rig: hardware fault: move to 180.0000°: alarm 0x0040 drive fault (power stage) at"),
            std::string::npos)
      << out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find("alarm      0x0040 drive fault"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " reset", out), 0) << out;
  EXPECT_NE(out.find("alarm      none"), std::string::npos) << out;
  EXPECT_EQ(rig("--modbus 127.0.0.1:1 --timeout 0.1 status", out), 4) << out;
  EXPECT_NE(out.find("cannot connect"), std::string::npos) << out;
}

TEST_F(RigTable, UsageErrorsExitWithTwo) {
  std::string out;
  EXPECT_EQ(rig("status", out), 2) << out;
  EXPECT_NE(out.find("say where the table is"), std::string::npos) << out;
  EXPECT_EQ(rig("--modbus nowhere status", out), 2) << out;
  EXPECT_EQ(rig(where_ + " move", out), 2) << out;
  EXPECT_EQ(rig(where_ + " --rtu /dev/null status", out), 2) << out;  // --modbus and --rtu exclude each other
}

TEST_F(RigTable, CtrlCDuringAMoveHaltsTheTableAndExitsThree) {
  std::string out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  // Slow the profile so the move is still running when the signal lands.
  ASSERT_EQ(run("mbpoll -m tcp -p " + server_.endpoint().substr(server_.endpoint().rfind(':') + 1) +
                    " -a 1 -0 -1 -t 4:int -B -r 10 127.0.0.1 20000",
                out),
            0)
      << out;
  int fd = -1;
  std::vector<std::string> argv = {RIG_BIN, "table", "--modbus", server_.endpoint().substr(4), "move", "300"};
  Child child(argv, &fd);
  for (int i = 0; i < 2000 && !emu_->snapshot().moving; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ASSERT_TRUE(emu_->snapshot().moving);
  ::kill(child.pid(), SIGINT);
  const int st = child.wait_status();
  close(fd);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 3);
  for (int i = 0; i < 500 && emu_->snapshot().moving; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_FALSE(emu_->snapshot().moving);
  EXPECT_LT(emu_->snapshot().position_deg, 100.0);
}

}  // namespace
}  // namespace rig::table_test
