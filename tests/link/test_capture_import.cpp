// `rig capture import` as a user runs it: a candump log (-l format, as can-utils writes
// it) through the hardware file's [dut] stream into a capture file, whose samples,
// header and gap report are checked, and which `rig analyze --input capture` then reads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "firmware_link/dbc.hpp"
#include "firmware_link/protocol.hpp"
#include "rig/capture/capture.hpp"

namespace fs = std::filesystem;
using namespace rig::link;

namespace {

fs::path dir() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / ("rig-capture-import-" + std::to_string(::getpid()));
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs the rig binary; returns its exit code, stdout and stderr in files beside `name`.
int run_rig(const std::string& args, const std::string& name) {
  const std::string cmd = std::string(RIG_BINARY) + " " + args + " > " + (dir() / (name + ".out")).string() + " 2> " +
                          (dir() / (name + ".err")).string();
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

std::string log_line(double t, const CanFrame& f) {
  char ts[40];
  std::snprintf(ts, sizeof ts, "(%.6f) vcan0 ", t);
  return ts + to_candump(f) + "\n";
}

float x_of(uint64_t k) { return static_cast<float>(static_cast<double>(k % 1000) * 1e-4 - 0.05); }

}  // namespace

TEST(CaptureImport, RigProtocolLogWithAGapAndADuplicate) {
  // 2000 samples at 1 kHz from counter 0xFFFF00 (the 24-bit wrap inside), samples
  // 500..509 lost, sample 800's X frame twice, heartbeats and a command in between.
  std::ostringstream log;
  const uint64_t k0 = 0xFFFF00;
  double t = 1732255200.0;
  log << log_line(t, encode(Command{Op::StartStream, 1, 0, 0, 0}));
  for (uint64_t i = 0; i < 2000; ++i, t += 1e-3) {
    const uint64_t k = k0 + i;
    if (i % 100 == 0) log << log_line(t, encode(Heartbeat{1, static_cast<uint8_t>(i / 100), 23.5, static_cast<uint32_t>(k)}));
    if (i >= 500 && i < 510) continue;
    const auto sx = StreamHalf{Channel::X, static_cast<uint32_t>(k & kSeqMask), stream_status::kFilterOn, x_of(k)};
    log << log_line(t, encode(sx));
    if (i == 800) log << log_line(t, encode(sx));
    log << log_line(t + 1e-4, encode(StreamHalf{Channel::Y, static_cast<uint32_t>(k & kSeqMask),
                                                stream_status::kFilterOn, -x_of(k)}));
  }
  std::ofstream(dir() / "rig.log") << log.str();
  std::ofstream(dir() / "hw.toml") << "[dut]\ncan = \"vcan0\"\n";

  const fs::path cap = dir() / "rig.rigcap";
  ASSERT_EQ(run_rig("capture import " + (dir() / "rig.log").string() + " --hardware " + (dir() / "hw.toml").string() +
                    " --out " + cap.string() + " --serial QPA-7 --orientation U20",
                "import"),
            0)
      << slurp(dir() / "import.err");
  const std::string out = slurp(dir() / "import.out");
  EXPECT_NE(out.find("1990 samples"), std::string::npos) << out;
  EXPECT_NE(out.find("gaps 1 (10 samples lost), duplicates 1"), std::string::npos) << out;
  EXPECT_NE(out.find("gap at seq " + std::to_string(k0 + 500) + ": 10 samples"), std::string::npos) << out;

  const auto c = rig::capture::load(cap.string());
  EXPECT_TRUE(c.recovery.complete);
  EXPECT_EQ(c.header.serial, "QPA-7");
  EXPECT_EQ(c.header.orientation, "U20");
  EXPECT_EQ(c.header.rate_hz, 1000.0);
  EXPECT_EQ(c.header.started, "2024-11-22T06:00:00Z");
  ASSERT_EQ(c.samples.size(), 1990u);
  for (const auto& s : c.samples) {
    EXPECT_EQ(s.x_g, x_of(s.seq));
    EXPECT_EQ(s.y_g, -x_of(s.seq));
    EXPECT_EQ((s.status & rig::sample_status::kGapBefore) != 0, s.seq == k0 + 510) << s.seq;
  }
  EXPECT_EQ(c.samples.back().seq, k0 + 1999);  // widened past 2^24

  ASSERT_EQ(run_rig("analyze " + cap.string() + " --input capture --json " + (dir() / "analysis.json").string(), "analyze"),
            0)
      << slurp(dir() / "analyze.err");
  EXPECT_NE(slurp(dir() / "analysis.json").find("\"capture\""), std::string::npos);
}

TEST(CaptureImport, DbcLayoutWith16BitCounterAndAnUnreadableLine) {
  // The ACC_XY layout of tests/data/dbc/dut-layouts.dbc: x and y in one extended-id,
  // big-endian frame, 16-bit counter wrapping inside the log.
  const Dbc db = Dbc::parse_file(std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/dut-layouts.dbc");
  const DbcMessage* m = db.find("ACC_XY");
  ASSERT_NE(m, nullptr);
  std::ostringstream log;
  double t = 100.0;  // relative time stamps: no start time in the header
  for (uint64_t k = 65000; k < 66500; ++k, t += 5e-4) {
    CanFrame f;
    f.id = m->id;
    f.extended = true;
    f.len = 8;
    std::span<uint8_t> d(f.data.data(), 8);
    dbc_insert_raw(d, 7, 16, true, k % 65536);
    dbc_insert_raw(d, 23, 24, true, dbc_raw_of(*m->signal("x"), x_of(k)));
    dbc_insert_raw(d, 47, 24, true, dbc_raw_of(*m->signal("y"), -x_of(k)));
    log << log_line(t, f);
    if (k == 65100) log << "(100.05) vcan0 garbage\n";
  }
  std::ofstream(dir() / "xy.log") << log.str();
  std::ofstream(dir() / "hw-xy.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << RIG_SOURCE_DIR
                                      << "/tests/data/dbc/dut-layouts.dbc\"\n[dut.stream]\ncounter = \"ACC_XY.cnt\"\n"
                                         "x = \"ACC_XY.x\"\ny = \"ACC_XY.y\"\nrate_hz = 2000\n";
  const fs::path cap = dir() / "xy.rigcap";
  EXPECT_EQ(run_rig("capture import " + (dir() / "xy.log").string() + " --hardware " + (dir() / "hw-xy.toml").string() +
                    " --out " + cap.string(),
                "xy"),
            2);  // the capture is written, the unreadable line named
  EXPECT_NE(slurp(dir() / "xy.err").find("xy.log:102: not a candump frame line"), std::string::npos)
      << slurp(dir() / "xy.err");
  const auto c = rig::capture::load(cap.string());
  ASSERT_EQ(c.samples.size(), 1500u);
  EXPECT_EQ(c.header.rate_hz, 2000.0);
  EXPECT_EQ(c.header.started, "");
  for (std::size_t i = 0; i < c.samples.size(); ++i) {
    EXPECT_EQ(c.samples[i].seq, 65000 + i);
    EXPECT_NEAR(c.samples[i].x_g, x_of(65000 + i), 2e-6);
  }
  ASSERT_EQ(run_rig("analyze " + cap.string() + " --input capture", "analyze-xy"), 0) << slurp(dir() / "analyze-xy.err");

  // A hardware file naming a signal the DBC lacks: exit 2 naming the file and line.
  std::ofstream(dir() / "hw-bad.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << RIG_SOURCE_DIR
                                       << "/tests/data/dbc/dut-layouts.dbc\"\n[dut.stream]\ncounter = \"ACC_XY.cnt\"\n"
                                          "x = \"ACC_XY.nope\"\n";
  EXPECT_EQ(run_rig("capture import " + (dir() / "xy.log").string() + " --hardware " + (dir() / "hw-bad.toml").string() +
                    " --out " + (dir() / "bad.rigcap").string(),
                "bad"),
            2);
  EXPECT_NE(slurp(dir() / "bad.err").find("hw-bad.toml:4:1: [dut.stream]: x = \"ACC_XY.nope\": no signal nope in ACC_XY"),
            std::string::npos)
      << slurp(dir() / "bad.err");
}
