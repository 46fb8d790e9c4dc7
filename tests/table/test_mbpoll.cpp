// A standard third-party Modbus master (mbpoll, from Debian) reading and
// writing the registers documented in docs/table-registers.md, over TCP and RTU.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <sstream>
#include <thread>

#include "helpers.hpp"
#include "plant/table/table_server.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

// Values mbpoll printed, by reference: lines like "[8]: \t900000".
// (std::regex trips GCC 12's -Wmaybe-uninitialized under the sanitizers.)
std::map<int, long> parse_values(const std::string& out) {
  std::map<int, long> v;
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    int ref = 0;
    long value = 0;
    if (std::sscanf(line.c_str(), "[%d]: %ld", &ref, &value) == 2) v[ref] = value;
  }
  return v;
}

bool wait_for(const std::function<bool()>& cond, double s = 10.0) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!cond()) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > s) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

class MbpollTcp : public ::testing::Test {
 protected:
  void SetUp() override {
    server_.start();
    const auto ep = m::parse_endpoint(server_.endpoint());
    base_ = "mbpoll -m tcp -p " + std::to_string(ep.port) + " -a 1 -0 -1 -o 2 ";
  }
  std::string mbpoll(const std::string& args, int* rc = nullptr) {
    std::string out;
    const int r = run(base_ + args, out);
    if (rc) {
      *rc = r;
    } else {
      EXPECT_EQ(r, 0) << base_ + args << "\n" << out;
    }
    return out;
  }
  std::unique_ptr<plant::TableEmulator> emu_ = emulator(kFastTable);
  plant::TableServer server_{*emu_, "tcp:127.0.0.1:0"};
  std::string base_;
};

TEST_F(MbpollTcp, ReadsTheDocumentedIdentityAndProfile) {
  auto v = parse_values(mbpoll("-t 4 -r 0 -c 4 127.0.0.1"));
  EXPECT_EQ(v[3], m::reg::kMapVersionValue);
  EXPECT_EQ(v[2], 0);                                              // no alarm
  EXPECT_NE(v[1] & m::sts::kReady, 0);
  v = parse_values(mbpoll("-t 4:int -B -r 10 -c 2 127.0.0.1"));  // velocity, acceleration (32-bit, high word first)
  EXPECT_EQ(v[10], 360000);
  EXPECT_EQ(v[12], 1800000);
  v = parse_values(mbpoll("-t 3 -r 3 -c 1 127.0.0.1"));            // input registers mirror the map
  EXPECT_EQ(v[3], m::reg::kMapVersionValue);
}

TEST_F(MbpollTcp, HomesAndMovesTheTableByHand) {
  mbpoll("-t 4 -r 0 127.0.0.1 1");   // servo on
  mbpoll("-t 4 -r 0 127.0.0.1 5");   // + home (rising edge)
  ASSERT_TRUE(wait_for([&] { return emu_->snapshot().homed && !emu_->snapshot().moving; }));
  mbpoll("-t 4:int -B -r 8 127.0.0.1 1234567");  // target 123.4567°
  mbpoll("-t 4 -r 0 127.0.0.1 1");
  mbpoll("-t 4 -r 0 127.0.0.1 3");   // + start (rising edge)
  ASSERT_TRUE(wait_for([&] { return emu_->snapshot().in_position; }));
  auto v = parse_values(mbpoll("-t 4:int -B -r 6 -c 2 127.0.0.1"));  // actual, target
  EXPECT_NEAR(v[6], 1234567, 10);
  EXPECT_EQ(v[8], 1234567);
  v = parse_values(mbpoll("-t 4 -r 1 -c 1 127.0.0.1"));
  EXPECT_NE(v[1] & m::sts::kInPosition, 0);
  EXPECT_NE(v[1] & m::sts::kHomed, 0);
  EXPECT_NEAR(emu_->actual_angle_deg(), 123.4567, 0.005);
}

TEST_F(MbpollTcp, SeesExceptionReplies) {
  int rc = 0;
  std::string out = mbpoll("-t 4 -r 1 127.0.0.1 7", &rc);  // status word is read-only
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("Illegal data address"), std::string::npos) << out;
  out = mbpoll("-t 4 -r 50 -c 1 127.0.0.1", &rc);          // hole in the map
  EXPECT_NE(out.find("Illegal data address"), std::string::npos) << out;
  out = mbpoll("-t 4:int -B -r 8 127.0.0.1 5000000", &rc);  // 500° is beyond the travel limit
  EXPECT_NE(out.find("Illegal data value"), std::string::npos) << out;
}

TEST_F(MbpollTcp, InjectsFaultsThroughTheMaintenanceBlock) {
  mbpoll("-t 4 -r 102 127.0.0.1 1");  // e-stop pressed
  emu_->step(0.01);
  auto v = parse_values(mbpoll("-t 4 -r 0 -c 3 127.0.0.1"));
  EXPECT_EQ(v[2], m::alarm::kEstop);
  EXPECT_NE(v[1] & m::sts::kEstop, 0);
  EXPECT_EQ(v[1] & m::sts::kReady, 0);
}

TEST(MbpollRtu, ReadsAndWritesOverAPtyPair) {
  PtyPair pty;
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "rtu:" + pty.a() + ",38400,E,8,1", 3);
  server.start();
  const std::string base = "mbpoll -m rtu -b 38400 -P even -a 3 -0 -1 -o 2 ";
  std::string out;
  ASSERT_EQ(run(base + "-t 4 -r 0 -c 4 " + pty.b(), out), 0) << out;
  EXPECT_EQ(parse_values(out)[3], m::reg::kMapVersionValue);
  ASSERT_EQ(run(base + "-t 4 -r 15 " + pty.b() + " 250", out), 0) << out;  // settle time 250 ms
  ASSERT_EQ(run(base + "-t 4 -r 15 -c 1 " + pty.b(), out), 0) << out;
  EXPECT_EQ(parse_values(out)[15], 250);
}

}  // namespace
}  // namespace rig::table_test
