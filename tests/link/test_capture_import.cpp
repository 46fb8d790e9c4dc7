// `rig capture import` as a user runs it: a candump log (-l format, as can-utils writes
// it) through the hardware file's [dut] stream into a capture file, whose samples,
// header and gap report are checked, and which `rig analyze --input capture` then reads.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "firmware_link/dbc.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "firmware_link/protocol.hpp"
#include "rig/capture/capture.hpp"
#include "tests/core/rig_process.hpp"

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

// Sample k in tests/data/dbc/dut-layouts.dbc's ACC_XY (`m`): x and y in one extended-id,
// big-endian frame with a 16-bit counter.
std::string acc_xy_line(const DbcMessage& m, double t, uint64_t k) {
  CanFrame f;
  f.id = m.id;
  f.extended = true;
  f.len = 8;
  std::span<uint8_t> d(f.data.data(), 8);
  dbc_insert_raw(d, 7, 16, true, k % 65536);
  dbc_insert_raw(d, 23, 24, true, dbc_raw_of(*m.signal("x"), x_of(k)));
  dbc_insert_raw(d, 47, 24, true, dbc_raw_of(*m.signal("y"), -x_of(k)));
  return log_line(t, f);
}

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

// The options are checked before the log is read (helper review): a capture already at --out is
// not replaced (it held 2000 samples; a second import of a shorter log replaced it silently), an
// --out in a folder that does not exist is a usage error (exit 2, was 4: "hardware fault"), and
// --rate outside the (0, 1 MHz] every reader accepts is refused (0 and -5 were ignored, 2e6
// written into a header rig analyze then refused).
TEST(CaptureImport, OptionsAreCheckedBeforeTheLogIsRead) {
  std::ofstream(dir() / "opts.log") << log_line(1732255200.0, encode(StreamHalf{Channel::X, 1, 0, 0.5f}));
  std::ofstream(dir() / "opts-hw.toml") << "[dut]\ncan = \"vcan0\"\n";
  const std::string head = "capture import " + (dir() / "opts.log").string() + " --hardware " +
                           (dir() / "opts-hw.toml").string() + " --out ";
  std::ofstream(dir() / "kept.rigcap") << "an earlier capture";
  EXPECT_EQ(run_rig(head + (dir() / "kept.rigcap").string(), "opts1"), 2);
  EXPECT_NE(slurp(dir() / "opts1.err").find("kept.rigcap: the file exists"), std::string::npos) << slurp(dir() / "opts1.err");
  EXPECT_EQ(slurp(dir() / "kept.rigcap"), "an earlier capture");

  // A folder as the log is named as such, exit 2 (it was exit 4, "basic_filebuf::underflow error
  // reading the file: Is a directory", the path not named: a review).
  fs::create_directories(dir() / "a-folder");
  EXPECT_EQ(run_rig("capture import " + (dir() / "a-folder").string() + " --hardware " + (dir() / "opts-hw.toml").string() +
                        " --out " + (dir() / "folder.rigcap").string(),
                    "opts-folder"),
            2);
  EXPECT_NE(slurp(dir() / "opts-folder.err").find((dir() / "a-folder").string() + ": is a folder, not a candump log"),
            std::string::npos)
      << slurp(dir() / "opts-folder.err");

  EXPECT_EQ(run_rig(head + (dir() / "no-such-folder" / "x.rigcap").string(), "opts2"), 2);
  EXPECT_NE(slurp(dir() / "opts2.err").find("does not exist"), std::string::npos) << slurp(dir() / "opts2.err");

  // Named as typed (1e-7 read "1e-07", a review).
  for (const char* rate : {"0", "-5", "2e6", "nan", "1e-7"}) {
    EXPECT_EQ(run_rig(head + (dir() / "rate.rigcap").string() + " --rate " + rate, "opts3"), 2) << rate;
    EXPECT_NE(slurp(dir() / "opts3.err").find("--rate: '" + std::string(rate) + "': "), std::string::npos)
        << slurp(dir() / "opts3.err");
    EXPECT_NE(slurp(dir() / "opts3.err").find("must be in [1e-06, 1000000] Hz"), std::string::npos) << slurp(dir() / "opts3.err");
    EXPECT_FALSE(fs::exists(dir() / "rate.rigcap")) << rate;
  }
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
    log << acc_xy_line(*m, t, k);
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
  EXPECT_NE(slurp(dir() / "bad.err").find("hw-bad.toml:6:5: [dut.stream]: x = \"ACC_XY.nope\": no signal nope in ACC_XY"),
            std::string::npos)
      << slurp(dir() / "bad.err");
}

// Two stations logged together (`candump -l any`): two DUTs' streams on can0 and can1 imported
// as one under one serial, exit 0 (a review). Without --iface the hardware file's [dut] can
// chooses, said; a file whose can is neither refuses, naming both, and writes nothing.
TEST(CaptureImport, StreamsOfTwoInterfacesAreNeverMixed) {
  const Dbc db = Dbc::parse_file(std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/dut-layouts.dbc");
  const DbcMessage* m = db.find("ACC_XY");
  ASSERT_NE(m, nullptr);
  std::ostringstream log;
  double t = 1732255200.0;
  for (uint64_t k = 0; k < 400; ++k, t += 5e-4) {
    std::string a = acc_xy_line(*m, t, k), b = acc_xy_line(*m, t + 1e-5, 30000 + k);
    log << a << b.replace(b.find("vcan0"), 5, "vcan1");
  }
  std::ofstream(dir() / "two.log") << log.str();
  const std::string layout = std::string("dbc = \"") + RIG_SOURCE_DIR +
                             "/tests/data/dbc/dut-layouts.dbc\"\n[dut.stream]\ncounter = \"ACC_XY.cnt\"\n"
                             "x = \"ACC_XY.x\"\ny = \"ACC_XY.y\"\nrate_hz = 2000\n";
  std::ofstream(dir() / "hw-two1.toml") << "[dut]\ncan = \"vcan1\"\n" << layout;
  std::ofstream(dir() / "hw-two9.toml") << "[dut]\ncan = \"can9\"\n" << layout;
  const std::string head = "capture import " + (dir() / "two.log").string() + " --hardware ";
  const fs::path cap = dir() / "two.rigcap";
  ASSERT_EQ(run_rig(head + (dir() / "hw-two1.toml").string() + " --out " + cap.string(), "two1"), 0)
      << slurp(dir() / "two1.err");
  EXPECT_NE(slurp(dir() / "two1.err").find("two.log: frames of the [dut] stream on vcan0 (from " +
                                           (dir() / "two.log").string() + ":1), vcan1 (from " +
                                           (dir() / "two.log").string() + ":2): importing vcan1's, the hardware "
                                           "file's [dut] can (--iface for another)"),
            std::string::npos)
      << slurp(dir() / "two1.err");
  const auto c = rig::capture::load(cap.string());
  ASSERT_EQ(c.samples.size(), 400u);
  EXPECT_EQ(c.samples.front().seq, 30000u) << "vcan1's DUT, not vcan0's";
  EXPECT_EQ(run_rig(head + (dir() / "hw-two9.toml").string() + " --out " + (dir() / "two9.rigcap").string(), "two9"),
            2);
  EXPECT_NE(slurp(dir() / "two9.err").find("the log holds more than one station's stream ("), std::string::npos)
      << slurp(dir() / "two9.err");
  EXPECT_NE(slurp(dir() / "two9.err").find("[dut] can is can9); give --iface with one of: vcan0, vcan1; "),
            std::string::npos)
      << slurp(dir() / "two9.err");
  EXPECT_FALSE(fs::exists(dir() / "two9.rigcap"));
  // --iface chooses either, whatever the file's can.
  ASSERT_EQ(run_rig(head + (dir() / "hw-two9.toml").string() + " --iface vcan0 --out " +
                        (dir() / "two0.rigcap").string(),
                    "two0"),
            0)
      << slurp(dir() / "two0.err");
  EXPECT_EQ(rig::capture::load((dir() / "two0.rigcap").string()).samples.front().seq, 0u);
  // A third interface, the file's own, appearing after the other two is still chosen (the choice
  // was made at the second, a code review); lines without an interface column are named so.
  std::string three = log.str();
  for (uint64_t k = 0; k < 400; ++k) {
    std::string line = acc_xy_line(*m, t + 1 + 5e-4 * k, 50000 + k);
    three += line.replace(line.find("vcan0"), 5, "vcan9");
  }
  std::ofstream(dir() / "three.log") << three << "(1732255300.000000) 18FF0001#0000\n";
  std::ofstream(dir() / "hw-three.toml") << "[dut]\ncan = \"vcan9\"\n" << layout;
  ASSERT_EQ(run_rig("capture import " + (dir() / "three.log").string() + " --hardware " +
                        (dir() / "hw-three.toml").string() + " --out " + (dir() / "three.rigcap").string(),
                    "three"),
            0)
      << slurp(dir() / "three.err");
  EXPECT_EQ(rig::capture::load((dir() / "three.rigcap").string()).samples.front().seq, 50000u);
  std::string bare = acc_xy_line(*m, t + 2, 60000);
  bare.erase(bare.find("vcan0 "), 6);
  std::ofstream(dir() / "bare.log") << log.str() << bare;
  EXPECT_EQ(run_rig("capture import " + (dir() / "bare.log").string() + " --hardware " + (dir() / "hw-two9.toml").string() +
                        " --out " + (dir() / "bare.rigcap").string(),
                    "bare"),
            2);
  EXPECT_NE(slurp(dir() / "bare.err").find("lines without an interface column (from "), std::string::npos)
      << slurp(dir() / "bare.err");
  EXPECT_NE(slurp(dir() / "bare.err").find("(lines without an interface cannot be chosen: split the log)"),
            std::string::npos)
      << slurp(dir() / "bare.err");
}

// The capture says which interface its stream came from, and the counts are that interface's,
// chosen by --iface or found: they were every interface's without --iface (a review).
TEST(CaptureImport, TheStreamsInterfaceIsInTheHeaderAndCountedAlone) {
  const Dbc db = Dbc::parse_file(std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/dut-layouts.dbc");
  const DbcMessage* m = db.find("ACC_XY");
  ASSERT_NE(m, nullptr);
  std::ostringstream log;
  double t = 1732255200.0;
  log << "(1732255198.000000) vcan0 18FF0001#00\n";  // another station's heartbeat, first in the log
  log << "(1732255199.000000) vcan1 18FF0002#00\n";  // this station's, before its stream
  for (uint64_t k = 0; k < 300; ++k, t += 5e-4) {
    std::string a = acc_xy_line(*m, t, k);
    log << a.replace(a.find("vcan0"), 5, "vcan1");
    if (k % 100 == 0) {
      char beats[96];
      std::snprintf(beats, sizeof beats, "(%.6f) vcan0 18FF0001#00\n(%.6f) vcan1 18FF0002#00\n", t, t);
      log << beats;
    }
  }
  std::ofstream(dir() / "iface.log") << log.str();
  std::ofstream(dir() / "hw-iface.toml") << "[dut]\ncan = \"can9\"\ndbc = \"" << RIG_SOURCE_DIR
                                         << "/tests/data/dbc/dut-layouts.dbc\"\n[dut.stream]\ncounter = "
                                            "\"ACC_XY.cnt\"\nx = \"ACC_XY.x\"\ny = \"ACC_XY.y\"\nrate_hz = 2000\n";
  const std::string head =
      "capture import " + (dir() / "iface.log").string() + " --hardware " + (dir() / "hw-iface.toml").string();
  ASSERT_EQ(run_rig(head + " --out " + (dir() / "found.rigcap").string(), "found"), 0) << slurp(dir() / "found.err");
  ASSERT_EQ(run_rig(head + " --iface vcan1 --out " + (dir() / "given.rigcap").string(), "given"), 0)
      << slurp(dir() / "given.err");
  const std::string found = slurp(dir() / "found.out"), given = slurp(dir() / "given.out");
  EXPECT_NE(found.find("300 samples from 300 stream frames (304 frames read on vcan1, 4 other ids)\n"
                       "4 frame(s) on other interfaces: not read\n"),
            std::string::npos)
      << found;
  auto counts = [](const std::string& out) { return out.substr(out.find(": ")); };  // past the file names
  EXPECT_EQ(counts(found), counts(given));
  for (const char* name : {"found.rigcap", "given.rigcap"}) {
    const auto c = rig::capture::load((dir() / name).string());
    EXPECT_EQ(c.header.extra.value("iface", ""), "vcan1") << name;
    EXPECT_EQ(c.header.started, "2024-11-22T05:59:59Z") << name << ": vcan1's first frame, not vcan0's";
  }
}

namespace {

// A CAN FD frame as candump -l / -L writes it: ID##F then the data, upper-case hex.
std::string fd_log_line(double t, const CanFdFrame& f) {
  char head[64];
  std::snprintf(head, sizeof head, f.extended ? "(%.6f) vcan0 %08X##%X" : "(%.6f) vcan0 %03X##%X", t, f.id,
                f.brs ? 1u : 0u);
  std::string s = head;
  for (int i = 0; i < f.len; ++i) {
    char b[3];
    std::snprintf(b, sizeof b, "%02X", f.data[static_cast<std::size_t>(i)]);
    s += b;
  }
  return s + "\n";
}

}  // namespace

// Issue 15, 3: CAN FD frames in candump logs, -l/-L format and (through can-utils' own
// log2long) the screen format: duts/qpa-fd.dbc's 7 samples per 64-byte frame, both formats
// imported into identical captures; a frame lost is one located gap of 7 samples.
TEST(CaptureImport, CanFdLayoutInBothCandumpFormats) {
  const std::string duts = std::string(RIG_SOURCE_DIR) + "/duts/";
  std::ofstream(dir() / "hw-fd.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << duts
                                      << "qpa-fd.dbc\"\n[dut.stream]\ncounter = \"QPA_FD.cnt\"\nx = \"QPA_FD.x\"\n"
                                         "y = \"QPA_FD.y\"\nstatus = \"QPA_FD.status\"\nfilter_on_bit = 0\n"
                                         "saturated_bit = 1\nsamples_per_frame = 7\n";
  DbcStreamSpec sp;
  sp.counter = "QPA_FD.cnt";
  sp.x = "QPA_FD.x";
  sp.y = "QPA_FD.y";
  sp.status = "QPA_FD.status";
  sp.filter_on_bit = 0;
  sp.samples_per_frame = 7;
  const DbcStreamEncoder enc(std::make_shared<const DbcStreamDecoder>(
      std::make_shared<const Dbc>(Dbc::parse_file(duts + "qpa-fd.dbc")), sp, "test"));
  std::ostringstream log;
  double t = 1732255200.0;
  const uint64_t k0 = 65536 - 7 * 100;  // the 16-bit counter wraps inside the log
  std::vector<CanFdFrame> frames;
  for (uint64_t b = 0; b < 300; ++b, t += 7e-3) {
    const uint64_t k = k0 + 7 * b;
    std::vector<StreamSample> s;
    for (uint64_t i = 0; i < 7; ++i) s.push_back({x_of(k + i), -x_of(k + i), stream_status::kFilterOn});
    frames.clear();
    enc.encode(static_cast<uint32_t>(k), s, frames);
    ASSERT_EQ(frames.size(), 1u);
    frames[0].brs = b % 2 == 0;  // the bit-rate switch flag is logged and does not matter
    if (b == 150) continue;      // one frame lost: 7 samples, after the wrap
    log << fd_log_line(t, frames[0]);
  }
  std::ofstream(dir() / "fd.log") << log.str();
  const fs::path cap = dir() / "fd.rigcap";
  ASSERT_EQ(run_rig("capture import " + (dir() / "fd.log").string() + " --hardware " + (dir() / "hw-fd.toml").string() +
                    " --out " + cap.string(),
                "fd"),
            0)
      << slurp(dir() / "fd.err");
  const auto c = rig::capture::load(cap.string());
  ASSERT_EQ(c.samples.size(), 7u * 299);
  EXPECT_EQ(c.samples.front().seq, k0);
  EXPECT_EQ(c.samples.back().seq, k0 + 7 * 300 - 1) << "widened past the 16-bit wrap";
  for (const auto& s : c.samples) {
    ASSERT_NEAR(s.x_g, x_of(s.seq), 1e-7) << s.seq;  // 0.01 ug counts
    ASSERT_NEAR(s.y_g, -x_of(s.seq), 1e-7) << s.seq;
  }
  const std::string out = slurp(dir() / "fd.out") + slurp(dir() / "fd.err");
  EXPECT_NE(out.find("gap at seq " + std::to_string(k0 + 7 * 150) + ": 7 samples"), std::string::npos) << out;

  // The screen format of the same frames, written by can-utils itself.
  ASSERT_EQ(std::system(("log2long < " + (dir() / "fd.log").string() + " > " + (dir() / "fd-screen.txt").string()).c_str()),
            0)
      << "log2long (can-utils) must be installed: scripts/setup";
  const std::string screen = slurp(dir() / "fd-screen.txt");
  ASSERT_NE(screen.find("[64]"), std::string::npos) << screen.substr(0, 300);
  const fs::path cap2 = dir() / "fd-screen.rigcap";
  ASSERT_EQ(run_rig("capture import " + (dir() / "fd-screen.txt").string() + " --hardware " +
                    (dir() / "hw-fd.toml").string() + " --out " + cap2.string(),
                "fd-screen"),
            0)
      << slurp(dir() / "fd-screen.err");
  const auto c2 = rig::capture::load(cap2.string());
  ASSERT_EQ(c2.samples.size(), c.samples.size());
  for (std::size_t i = 0; i < c.samples.size(); ++i) {
    ASSERT_EQ(c2.samples[i].seq, c.samples[i].seq);
    ASSERT_EQ(c2.samples[i].x_g, c.samples[i].x_g);
    ASSERT_EQ(c2.samples[i].y_g, c.samples[i].y_g);
    ASSERT_EQ(c2.samples[i].status, c.samples[i].status);
  }
}

// A log with no sample of the [dut] stream (only commands and heartbeats; or --iface naming no
// frame) writes no capture and exits 2 naming the log: an empty capture would fail only later,
// in rig analyze, far from the cause (found by a newcomer's review).
TEST(CaptureImport, ALogWithoutTheStreamWritesNoCaptureAndExits2) {
  std::ostringstream log;
  double t = 1732255200.0;
  log << log_line(t, encode(Command{Op::StartStream, 1, 0, 0, 0}));
  for (int i = 0; i < 5; ++i, t += 0.1) log << log_line(t, encode(Heartbeat{1, static_cast<uint8_t>(i), 23.5, 0}));
  std::ofstream(dir() / "nostream.log") << log.str();
  std::ofstream(dir() / "hw-ns.toml") << "[dut]\ncan = \"vcan0\"\n";
  const fs::path cap = dir() / "nostream.rigcap";
  EXPECT_EQ(run_rig("capture import " + (dir() / "nostream.log").string() + " --hardware " + (dir() / "hw-ns.toml").string() +
                        " --out " + cap.string(),
                    "nostream"),
            2);
  EXPECT_FALSE(fs::exists(cap));
  const std::string err = slurp(dir() / "nostream.err");
  EXPECT_NE(err.find("nostream.log: no sample of the [dut] stream"), std::string::npos) << err;
  // Its frames are counted as read on the DUT's interface and of other ids: "on other interfaces"
  // sent a review after --iface where the DBC was wrong. The same where the hardware file names
  // an interface the log does not have (the log's one interface is then the DUT's).
  const std::string out = slurp(dir() / "nostream.out");
  EXPECT_NE(out.find("(6 frames read on vcan0, 6 other ids)"), std::string::npos) << out;
  EXPECT_EQ(out.find("other interfaces"), std::string::npos) << out;
  std::ofstream(dir() / "hw-ns1.toml") << "[dut]\ncan = \"can1\"\n";
  EXPECT_EQ(run_rig("capture import " + (dir() / "nostream.log").string() + " --hardware " +
                        (dir() / "hw-ns1.toml").string() + " --out " + cap.string(),
                    "nostream1"),
            2);
  const std::string out1 = slurp(dir() / "nostream1.out");
  EXPECT_NE(out1.find("(6 frames read on vcan0, 6 other ids)"), std::string::npos) << out1;
  EXPECT_NE(slurp(dir() / "nostream.err").find("in the 6 frame(s) read on vcan0; "), std::string::npos)
      << slurp(dir() / "nostream.err");
  // --iface naming an interface without frames: the line says what the summary says, 0 read
  // there and the rest elsewhere (it said "in 6 frame(s) on can1": a review).
  EXPECT_EQ(run_rig("capture import " + (dir() / "nostream.log").string() + " --hardware " +
                        (dir() / "hw-ns.toml").string() + " --out " + cap.string() + " --iface can1",
                    "nostream2"),
            2);
  const std::string err2 = slurp(dir() / "nostream2.err");
  EXPECT_NE(err2.find("in the 0 frame(s) read on can1 (6 on other interfaces, not read: is --iface can1 the DUT's?); "),
            std::string::npos)
      << err2;
}

// An import that does not finish (a full disk here: the file size limit, as `ulimit -f`) leaves
// nothing under --out: a partial capture was left there, which rig analyze read as a shorter
// record and a retry was refused over (a technician's review). The capture is written as OUT.part
// and takes its name only when kept; the retry then imports the whole log.
TEST(CaptureImport, AnImportThatDoesNotFinishLeavesNoCapture) {
  std::ostringstream log;
  double t = 1732255200.0;
  for (uint64_t k = 0; k < 20000; ++k, t += 1e-3) {
    log << log_line(t, encode(StreamHalf{Channel::X, static_cast<uint32_t>(k), 0, x_of(k)}));
    log << log_line(t + 1e-4, encode(StreamHalf{Channel::Y, static_cast<uint32_t>(k), 0, -x_of(k)}));
  }
  std::ofstream(dir() / "cut.log") << log.str();
  std::ofstream(dir() / "hw-cut.toml") << "[dut]\ncan = \"vcan0\"\n";
  const fs::path cap = dir() / "cut.rigcap";
  const std::string import =
      "capture import " + (dir() / "cut.log").string() + " --hardware " + (dir() / "hw-cut.toml").string() + " --out " + cap.string();
  // 64 KiB at most per file (ulimit -f counts 1 KiB blocks; SIGXFSZ ignored: the write fails, EFBIG).
  const std::string limited = "ulimit -f 64; trap '' XFSZ; " + std::string(RIG_BINARY) + " " + import + " >'" +
                              (dir() / "cut.out").string() + "' 2>'" + (dir() / "cut.err").string() + "'";
  const int st = std::system(limited.c_str());
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_NE(WEXITSTATUS(st), 0);
  const std::string err = slurp(dir() / "cut.err");
  EXPECT_NE(err.find("File too large"), std::string::npos) << err;
  EXPECT_NE(err.find("rig capture import: " + cap.string() + " not written (the import did not finish)"), std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(cap));
  const auto staged_left = [&](const fs::path& out) {
    for (const auto& e : fs::directory_iterator(dir()))
      if (e.path().filename().string().rfind(out.filename().string() + ".part", 0) == 0) return true;
    return false;
  };
  EXPECT_FALSE(staged_left(cap));
  // Stopped by SIGTERM while it writes (the signal's exit in main.cpp): exit 3, nothing under
  // --out, the staged file gone too. The log is long enough (600 000 lines) to be stopped in.
  {
    std::ofstream big(dir() / "long.log");
    double tl = 1732255200.0;
    for (uint64_t k = 0; k < 300000; ++k, tl += 1e-3) {
      big << log_line(tl, encode(StreamHalf{Channel::X, static_cast<uint32_t>(k & kSeqMask), 0, x_of(k)}));
      big << log_line(tl + 1e-4, encode(StreamHalf{Channel::Y, static_cast<uint32_t>(k & kSeqMask), 0, -x_of(k)}));
    }
  }
  const fs::path stopped = dir() / "stopped.rigcap";
  // The long log's import into `out`, started (rig_process.hpp: stderr to dir()/NAME.stderr).
  const auto import_long = [&](const fs::path& out, const std::string& name) {
    return rig::test::spawn({"capture", "import", (dir() / "long.log").string(), "--hardware",
                             (dir() / "hw-cut.toml").string(), "--out", out.string()},
                            (dir() / name).string());
  };
  const rig::test::Child first = import_long(stopped, "stopped");
  ASSERT_TRUE(rig::test::wait_for_file(first, stopped.string() + ".part-" + std::to_string(first.pid)));  // its own
  ::kill(first.pid, SIGTERM);
  EXPECT_EQ(rig::test::wait_exit(first), 3) << slurp(dir() / "stopped.stderr");
  EXPECT_NE(slurp(dir() / "stopped.stderr").find("rig: aborted: SIGTERM\nrig capture import: " + stopped.string() +
                                                  " not written (the import did not finish)"),
            std::string::npos)
      << slurp(dir() / "stopped.stderr");
  EXPECT_FALSE(fs::exists(stopped));
  EXPECT_FALSE(staged_left(stopped));
  // Its record is the capture: a summary that cannot be printed (> /dev/full) is not exit 2 with
  // the capture written, whose retry is then refused for the file that exists (a re-test).
  const int full = std::system((std::string(RIG_BINARY) + " " + import + " >/dev/full 2>'" +
                                (dir() / "full.err").string() + "'").c_str());
  EXPECT_TRUE(WIFEXITED(full) && WEXITSTATUS(full) == 0) << full << slurp(dir() / "full.err");
  EXPECT_TRUE(fs::exists(cap));
  fs::remove(cap);
  ASSERT_EQ(run_rig(import, "cut-again"), 0) << slurp(dir() / "cut-again.err");
  EXPECT_NE(slurp(dir() / "cut-again.out").find("20000 samples"), std::string::npos) << slurp(dir() / "cut-again.out");
  EXPECT_TRUE(fs::exists(cap));
  EXPECT_FALSE(staged_left(cap));
  // Killed outright (SIGKILL), an import leaves OUT.part-PID; the next import to that name says
  // it is a partial file and leaves it (a re-test: it sat there unnamed), and one running is not named.
  const fs::path killed = dir() / "killed.rigcap";
  const rig::test::Child fourth = import_long(killed, "killed");
  const std::string staged4 = killed.string() + ".part-" + std::to_string(fourth.pid);
  ASSERT_TRUE(rig::test::wait_for_file(fourth, staged4));
  ::kill(fourth.pid, SIGKILL);
  rig::test::wait_exit(fourth);
  const std::string reused = killed.string() + ".part-" + std::to_string(::getpid());
  std::ofstream(reused) << "a partial file";
  const rig::test::Child running = import_long(killed, "running");
  ASSERT_TRUE(rig::test::wait_for_file(running, killed.string() + ".part-" + std::to_string(running.pid)));
  ASSERT_EQ(run_rig("capture import " + (dir() / "cut.log").string() + " --hardware " + (dir() / "hw-cut.toml").string() +
                        " --out " + killed.string(),
                    "after-kill"),
            0)
      << slurp(dir() / "after-kill.err");
  ::kill(running.pid, SIGTERM);
  rig::test::wait_exit(running);
  const std::string after_kill = slurp(dir() / "after-kill.err");
  EXPECT_NE(after_kill.find("rig capture import: " + staged4 + " is left from an import that did not finish (no import "
                            "writes it now): a partial file, not a capture; remove it\n"),
            std::string::npos)
      << after_kill;
  // Its number reused by a process that is no import (this test's own: not a rig, no lock on the
  // file): left over all the same.
  EXPECT_NE(after_kill.find(reused + " is left from an import that did not finish"), std::string::npos) << after_kill;
  EXPECT_EQ(after_kill.find(".part-" + std::to_string(running.pid)), std::string::npos) << after_kill;
  EXPECT_TRUE(fs::exists(staged4));
  EXPECT_TRUE(fs::exists(killed));
  // A file that appears under --out during the import (another import to the same name, which
  // writes its own staged file: they shared OUT.part, and one set the other's aside or unlinked it,
  // a code review) is never replaced: this capture stays staged, named, exit 2.
  const fs::path twice = dir() / "twice.rigcap";
  const rig::test::Child second = import_long(twice, "twice");
  const std::string staged2 = twice.string() + ".part-" + std::to_string(second.pid);
  ASSERT_TRUE(rig::test::wait_for_file(second, staged2));
  std::ofstream(twice) << "another import's capture";
  EXPECT_EQ(rig::test::wait_exit(second), 2) << slurp(dir() / "twice.stderr");
  EXPECT_NE(slurp(dir() / "twice.stderr").find("--out " + twice.string() + ": a file appeared there during the import; "
                                               "the capture is kept as " + staged2),
            std::string::npos)
      << slurp(dir() / "twice.stderr");
  EXPECT_EQ(slurp(twice), "another import's capture");
  EXPECT_GT(fs::file_size(staged2), 1000000u);
  // That kept capture is whole: the next import to that name says so, not "partial" (a code
  // review: a technician told to remove it would have lost the capture).
  fs::remove(twice);
  ASSERT_EQ(run_rig("capture import " + (dir() / "cut.log").string() + " --hardware " + (dir() / "hw-cut.toml").string() +
                        " --out " + twice.string(),
                    "after-kept"),
            0)
      << slurp(dir() / "after-kept.err");
  EXPECT_NE(slurp(dir() / "after-kept.err")
                .find("rig capture import: " + staged2 + " is a whole capture an earlier import kept under its staged "
                      "name (no import writes it now): rename it to use it, to a name other than " + twice.string() +
                      ", which this import writes\n"),
            std::string::npos)
      << slurp(dir() / "after-kept.err");
  EXPECT_EQ(slurp(dir() / "after-kept.err").find("partial"), std::string::npos) << slurp(dir() / "after-kept.err");
  // --out's folder removed, or renamed, during the import: said so, exit 2, and nothing left in
  // the folder's new place ("kept as" named a path that was gone, and a renamed folder kept the
  // staged file while the message said "nothing kept": reviews).
  for (const bool renamed : {false, true}) {
    const std::string tag = renamed ? "moved" : "gone";
    fs::create_directories(dir() / tag);
    const fs::path out = dir() / tag / "g.rigcap";
    const rig::test::Child third = import_long(out, tag);
    ASSERT_TRUE(rig::test::wait_for_file(third, out.string() + ".part-" + std::to_string(third.pid)));
    if (renamed) fs::rename(dir() / tag, dir() / (tag + "-away"));
    else fs::remove_all(dir() / tag);
    const int exit_code = rig::test::wait_exit(third);
    const std::string said = slurp(dir() / (tag + ".stderr"));
    EXPECT_EQ(exit_code, 2) << said;
    EXPECT_NE(said.find("--out " + out.string() + ": its folder " + (dir() / tag).string() + " was removed or renamed "
                       "during the import: the capture written there is removed, nothing kept"),
              std::string::npos)
        << said;
    EXPECT_EQ(said.find("kept as"), std::string::npos) << said;
    if (renamed) {
      EXPECT_TRUE(fs::is_empty(dir() / (tag + "-away")));
    }
  }
}

namespace {

// A rig-protocol sample as two log lines (X, then Y 0.1 ms later).
void log_sample(std::ostringstream& log, double t, uint64_t k, bool with_y = true) {
  const auto seq = static_cast<uint32_t>(k & kSeqMask);
  log << log_line(t, encode(StreamHalf{Channel::X, seq, 0, x_of(k)}));
  if (with_y) log << log_line(t + 1e-4, encode(StreamHalf{Channel::Y, seq, 0, -x_of(k)}));
}

}  // namespace

// A review's logs (helper-54): a DUT that restarted mid-log (its counter back at 0), or a pause
// longer than half the counter's period, was spliced on as if no time had passed or silently
// dropped as "duplicates" with exit 0. Now the capture ends at that line, exit 2 names it and
// the line to import the rest from, and the rest imports with --from-line.
TEST(CaptureImport, ARestartOrAPauseTheCounterCannotSpanEndsTheCaptureThere) {
  std::ofstream(dir() / "hw-rs.toml") << "[dut]\ncan = \"vcan0\"\n";
  const std::string hw = " --hardware " + (dir() / "hw-rs.toml").string();
  std::ostringstream log;
  double t = 1732255200.0;
  for (uint64_t k = 5000000; k < 5000300; ++k, t += 1e-3) log_sample(log, t, k);  // lines 1..600
  for (uint64_t k = 0; k < 200; ++k, t += 1e-3) log_sample(log, t, k);              // from line 601
  std::ofstream(dir() / "restart.log") << log.str();
  const std::string out = (dir() / "restart.rigcap").string();
  EXPECT_EQ(run_rig("capture import " + (dir() / "restart.log").string() + hw + " --out " + out, "restart"), 2);
  const std::string err = slurp(dir() / "restart.err");
  EXPECT_NE(err.find("restart.log:601: the stream's counter went back from 5000299 to 0 (the DUT restarted?)"),
            std::string::npos) << err;
  EXPECT_NE(err.find("holds the 300 sample(s) before it; import the rest into another capture with --from-line 601"),
            std::string::npos) << err;
  EXPECT_NE(slurp(dir() / "restart.out").find("300 samples from 600 stream frames (600 frames read"), std::string::npos)
      << slurp(dir() / "restart.out");
  auto c = rig::capture::load(out);
  ASSERT_EQ(c.samples.size(), 300u);
  EXPECT_EQ(c.samples.back().seq, 5000299u);
  const std::string rest = (dir() / "restart-rest.rigcap").string();
  ASSERT_EQ(run_rig("capture import " + (dir() / "restart.log").string() + hw + " --out " + rest + " --from-line 601",
                    "rest"),
            0) << slurp(dir() / "rest.err");
  c = rig::capture::load(rest);
  ASSERT_EQ(c.samples.size(), 200u);
  EXPECT_EQ(c.samples.front().seq, 0u);
  EXPECT_EQ(c.header.started, "2024-11-22T06:00:00Z");  // the first imported line's second
  // Past the log's end: said so, with the log's length (it read "no sample ... in 0 frame(s)").
  const std::string past = (dir() / "restart-past.rigcap").string();
  EXPECT_EQ(run_rig("capture import " + (dir() / "restart.log").string() + hw + " --out " + past + " --from-line 1001",
                    "past"),
            2);
  EXPECT_NE(slurp(dir() / "past.err").find("restart.log: --from-line 1001 is past the log's end: it has 1000 line(s); " +
                                           past + " not written"),
            std::string::npos)
      << slurp(dir() / "past.err");
  EXPECT_FALSE(fs::exists(past));
  EXPECT_EQ(slurp(dir() / "past.out"), "") << "no summary of nothing";
  // An empty log without --from-line is a log with no sample, not one --from-line 1 is past.
  std::ofstream(dir() / "empty.log").flush();
  EXPECT_EQ(run_rig("capture import " + (dir() / "empty.log").string() + hw + " --out " + past, "empty"), 2);
  EXPECT_NE(slurp(dir() / "empty.err").find("empty.log: no sample of the [dut] stream"), std::string::npos)
      << slurp(dir() / "empty.err");
  {
    // The same with other interfaces' frames and an unreadable line before the restart: the counts
    // taken back at the cut are each their own (two were swapped: 29 blank problem lines and one
    // frame on other interfaces for 30; a code review).
    std::ostringstream mixed;
    double tm = 1732255200.0;
    mixed << "garbage\n";
    for (uint64_t k = 5000000; k < 5000300; ++k, tm += 1e-3) {
      log_sample(mixed, tm, k);
      if (k < 5000030) mixed << "(" << std::to_string(tm) << ") vcan1 123#00\n";
    }
    for (uint64_t k = 0; k < 200; ++k, tm += 1e-3) log_sample(mixed, tm, k);
    std::ofstream(dir() / "restart-mixed.log") << mixed.str();
    EXPECT_EQ(run_rig("capture import " + (dir() / "restart-mixed.log").string() + hw + " --iface vcan0 --out " +
                          (dir() / "restart-mixed.rigcap").string(),
                      "restart-mixed"),
              2);
    const std::string mout = slurp(dir() / "restart-mixed.out"), merr = slurp(dir() / "restart-mixed.err");
    EXPECT_NE(mout.find("30 frame(s) on other interfaces: not read"), std::string::npos) << mout;
    EXPECT_NE(merr.find("restart-mixed.log:1: "), std::string::npos) << merr;
    EXPECT_EQ(merr.find("\n\n"), std::string::npos) << "no blank problem lines:\n" << merr;
  }

  // A 16-bit counter and a 40 s pause (more than its 32.8 s half period at 1 kHz): the widening
  // cannot tell how many periods passed, the log's clock says so.
  const Dbc db = Dbc::parse_file(std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/dut-layouts.dbc");
  const DbcMessage* m = db.find("ACC_XY");
  ASSERT_NE(m, nullptr);
  auto xy = [&](double tt, uint64_t k) { return acc_xy_line(*m, tt, k); };
  std::ostringstream p;
  t = 1732255200.0;
  for (uint64_t k = 0; k < 100; ++k, t += 1e-3) p << xy(t, k);
  t += 40;
  for (uint64_t k = 40100; k < 40200; ++k, t += 1e-3) p << xy(t, k);  // the DUT counted on: 40000 past
  std::ofstream(dir() / "pause.log") << p.str();
  std::ofstream(dir() / "hw-p.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << RIG_SOURCE_DIR
                                     << "/tests/data/dbc/dut-layouts.dbc\"\n[dut.stream]\ncounter = \"ACC_XY.cnt\"\n"
                                        "x = \"ACC_XY.x\"\ny = \"ACC_XY.y\"\nrate_hz = 1000\n";
  EXPECT_EQ(run_rig("capture import " + (dir() / "pause.log").string() + " --hardware " + (dir() / "hw-p.toml").string() +
                        " --out " + (dir() / "pause.rigcap").string(),
                    "pause"),
            2);
  const std::string perr = slurp(dir() / "pause.err");
  EXPECT_NE(perr.find("pause.log:101: 40.001 s passed since the stream's last frame (40001 samples at 1000 Hz), more "
                      "than half the 16-bit counter's period"),
            std::string::npos) << perr;
  EXPECT_EQ(rig::capture::load((dir() / "pause.rigcap").string()).samples.size(), 100u);
  EXPECT_NE(slurp(dir() / "pause.out").find("rate 1000 Hz (" + (dir() / "hw-p.toml").string() + ":8:11: [dut.stream])"),
            std::string::npos) << slurp(dir() / "pause.out");
}

// Also from helper-54: one frame logged further behind than the reorder window, with the stream
// going on after it, is a stray late frame (counted apart, not a restart, not a "duplicate"); the
// first sample logged a little late takes its place at the start; a tail of samples with x but no
// y is said; FD frames on the rig protocol's ids are another node's (the live link skips them too).
TEST(CaptureImport, LateFramesTheTailAndFdFramesAreAccountedFor) {
  std::ofstream(dir() / "hw-late.toml") << "[dut]\ncan = \"vcan0\"\n";
  std::ostringstream log;
  double t = 1732255200.0;
  log_sample(log, t, 1001);
  log_sample(log, t + 1e-3, 1002);
  log_sample(log, t + 2e-3, 1000);  // the first sample, two samples late: within the window
  for (uint64_t k = 1003; k < 1100; ++k) log_sample(log, t + static_cast<double>(k - 1000) * 1e-3, k);
  log_sample(log, t + 0.1, 1050);  // 50 behind: a stray sample, its two frames
  CanFdFrame fd;
  fd.fd = true;
  fd.id = 0x100;
  fd.len = 12;
  log << fd_log_line(t + 0.1, fd);  // on DUT_STREAM_X's id, but FD: not the rig protocol's
  for (uint64_t k = 1100; k < 1200; ++k) log_sample(log, t + static_cast<double>(k - 1000) * 1e-3, k);
  for (uint64_t k = 1200; k < 1203; ++k) log_sample(log, t + 0.2, k, false);  // the tail: x only
  std::ofstream(dir() / "late.log") << log.str();
  const fs::path cap = dir() / "late.rigcap";
  ASSERT_EQ(run_rig("capture import " + (dir() / "late.log").string() + " --hardware " +
                        (dir() / "hw-late.toml").string() + " --out " + cap.string(),
                    "late"),
            0) << slurp(dir() / "late.err");
  const std::string out = slurp(dir() / "late.out");
  EXPECT_NE(out.find("200 samples"), std::string::npos) << out;
  EXPECT_NE(out.find("(406 frames read on vcan0, 1 other ids)"), std::string::npos) << out;
  EXPECT_NE(out.find("gaps 0 (0 samples lost), duplicates 0\n"), std::string::npos) << out;
  EXPECT_NE(out.find("2 frame(s) logged more than the reorder window (8 samples) behind the stream"), std::string::npos)
      << out;
  EXPECT_NE(out.find("rate 1000 Hz (the rig protocol's)"), std::string::npos) << out;
  EXPECT_NE(out.find("3 incomplete sample(s) at the end (a part without its partner)"), std::string::npos) << out;
  const auto c = rig::capture::load(cap.string());
  ASSERT_EQ(c.samples.size(), 200u);
  for (std::size_t i = 0; i < c.samples.size(); ++i) EXPECT_EQ(c.samples[i].seq, 1000 + i);
}

// A log whose clock stepped back (an NTP step of the station's clock during candump -l, or lines
// merged out of order) was imported without a word, though every pause and leap is judged on
// that clock (carried in session 34's note): the frames stamped earlier than the clock had
// reached are counted and the first named; the samples stay where their counter puts them.
TEST(CaptureImport, StampsThatGoBackAreSaid) {
  std::ofstream(dir() / "hw-back.toml") << "[dut]\ncan = \"vcan0\"\n";
  std::ostringstream log;
  double t = 1732255200.0;
  for (uint64_t k = 0; k < 100; ++k, t += 1e-3) log_sample(log, t, k);  // lines 1..200
  t -= 2.5;                                                            // the clock steps back
  for (uint64_t k = 100; k < 200; ++k, t += 1e-3) log_sample(log, t, k);
  std::ofstream(dir() / "back.log") << log.str();
  const fs::path cap = dir() / "back.rigcap";
  ASSERT_EQ(run_rig("capture import " + (dir() / "back.log").string() + " --hardware " +
                        (dir() / "hw-back.toml").string() + " --out " + cap.string(),
                    "back"),
            0) << slurp(dir() / "back.err");
  const std::string out = slurp(dir() / "back.out");
  EXPECT_NE(out.find("200 stream frame(s) stamped earlier than a frame before them (the first at " +
                     (dir() / "back.log").string() + ":201, 2.4991 s back): the log's lines are out of order or its "
                     "clock stepped back; samples are placed by their counter\n"),
            std::string::npos) << out;
  EXPECT_NE(out.find("gaps 0 (0 samples lost), duplicates 0\n"), std::string::npos) << out;
  EXPECT_EQ(rig::capture::load(cap.string()).samples.size(), 200u);
}

// Also from helper-54: a counter too small for the reorder window is refused at the hardware
// file's line with the key to change (it was the reassembler's bare message), and a line no
// candump writes (megabytes without a newline: `/dev/zero` grew the process without bound) is
// named and read past in bounded memory.
TEST(CaptureImport, ASmallCounterAndAnEndlessLineAreNamed) {
  std::ofstream(dir() / "c3.dbc") << "VERSION \"\"\n\nBU_: DUT\n\nBO_ 291 ACC: 8 DUT\n"
                                     " SG_ cnt : 0|3@1+ (1,0) [0|7] \"\" Vector__XXX\n"
                                     " SG_ x : 8|32@1- (1e-06,0) [-2000|2000] \"g\" Vector__XXX\n";
  std::ofstream(dir() / "hw-c3.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"c3.dbc\"\n[dut.stream]\ncounter = \"ACC.cnt\"\n"
                                         "x = \"ACC.x\"\n";
  std::ostringstream log;
  for (int k = 0; k < 20; ++k) {
    char line[80];
    std::snprintf(line, sizeof line, "(1732255200.%06d) vcan0 123#%02X00000000000000\n", k * 1000, k % 8);
    log << line;
  }
  std::ofstream(dir() / "c3.log") << log.str();
  const std::string args = "capture import " + (dir() / "c3.log").string() + " --hardware ";
  EXPECT_EQ(run_rig(args + (dir() / "hw-c3.toml").string() + " --out " + (dir() / "c3.rigcap").string(), "c3"), 2);
  EXPECT_NE(slurp(dir() / "c3.err").find("hw-c3.toml:4:1: [dut.stream]: a reorder window of 8 samples is more than half "
                                         "the 3-bit counter's period (4): set [dut] reorder_window to at most that"),
            std::string::npos) << slurp(dir() / "c3.err");
  std::ofstream(dir() / "hw-c3w.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"c3.dbc\"\nreorder_window = 4\n[dut.stream]\n"
                                          "counter = \"ACC.cnt\"\nx = \"ACC.x\"\n";
  ASSERT_EQ(run_rig(args + (dir() / "hw-c3w.toml").string() + " --out " + (dir() / "c3w.rigcap").string(), "c3w"), 0)
      << slurp(dir() / "c3w.err");
  EXPECT_EQ(rig::capture::load((dir() / "c3w.rigcap").string()).samples.size(), 20u);
  // A stream without y: its capture says so, not "20 sample(s) with a non-finite value".
  const std::string c3w = (dir() / "c3w.rigcap").string();
  ASSERT_EQ(run_rig("analyze " + c3w + " --input capture", "c3w-an"), 0) << slurp(dir() / "c3w-an.err");
  EXPECT_NE(slurp(dir() / "c3w-an.out").find("complete; y is NaN on every sample (a stream without y)\n"), std::string::npos)
      << slurp(dir() / "c3w-an.out");
  EXPECT_EQ(run_rig("analyze " + c3w + " --input capture --channel y", "c3w-y"), 2);
  EXPECT_NE(slurp(dir() / "c3w-y.err").find("channel y is NaN on every sample (a stream without y): nothing to analyse"), std::string::npos)
      << slurp(dir() / "c3w-y.err");

  std::ofstream(dir() / "long.log") << log.str().substr(0, log.str().find('\n') + 1) << std::string(1 << 20, 'A') << "\n"
                                    << log.str().substr(log.str().find('\n') + 1);
  EXPECT_EQ(run_rig("capture import " + (dir() / "long.log").string() + " --hardware " + (dir() / "hw-c3w.toml").string() +
                        " --out " + (dir() / "long.rigcap").string(),
                    "long"),
            2);
  EXPECT_NE(slurp(dir() / "long.err").find("long.log:2: a line longer than 4096 characters: not a candump log line"),
            std::string::npos) << slurp(dir() / "long.err");
  EXPECT_EQ(rig::capture::load((dir() / "long.rigcap").string()).samples.size(), 20u);
}

// A code review's logs (helper-55): two stray samples in a row are strays, not a restart; a
// restart after the counter passed half its period widens to a leap forward, which the log's
// clock gives away; a restart before any whole sample writes no capture and still gives the
// line; a sample missing its Y in the middle is a gap, not an "incomplete sample at the end";
// a log that begins between a sample's X and Y starts at its first whole sample, no gap.
TEST(CaptureImport, StraysLeapsAndPartsAreToldApart) {
  std::ofstream(dir() / "hw-sl.toml") << "[dut]\ncan = \"vcan0\"\n";
  auto import = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir() / (name + ".log")) << text;
    return run_rig("capture import " + (dir() / (name + ".log")).string() + " --hardware " +
                       (dir() / "hw-sl.toml").string() + " --out " + (dir() / (name + ".rigcap")).string(),
                   name);
  };
  const double t0 = 1732255200.0;
  std::ostringstream strays;
  for (uint64_t k = 1000; k < 1100; ++k) log_sample(strays, t0 + static_cast<double>(k - 1000) * 1e-3, k);
  log_sample(strays, t0 + 0.1, 1050);
  log_sample(strays, t0 + 0.1, 1051);
  for (uint64_t k = 1100; k < 1200; ++k) log_sample(strays, t0 + static_cast<double>(k - 1000) * 1e-3, k);
  ASSERT_EQ(import("strays", strays.str()), 0) << slurp(dir() / "strays.err");
  EXPECT_NE(slurp(dir() / "strays.out").find("4 frame(s) logged more than the reorder window"), std::string::npos)
      << slurp(dir() / "strays.out");
  EXPECT_EQ(rig::capture::load((dir() / "strays.rigcap").string()).samples.size(), 200u);

  std::ostringstream leap;
  double t = t0;
  for (uint64_t k = 9000000; k < 9000100; ++k, t += 1e-3) log_sample(leap, t, k);
  t += 3;
  for (uint64_t k = 0; k < 100; ++k, t += 1e-3) log_sample(leap, t, k);  // 2^24 - 9e6 + 0 ahead
  EXPECT_EQ(import("leap", leap.str()), 2);
  EXPECT_NE(slurp(dir() / "leap.err").find("leap.log:201: the stream's counter leapt 7777117 samples (7777.12 s at "
                                           "1000 Hz) where the log's clock moved 3.0"),
            std::string::npos) << slurp(dir() / "leap.err");
  EXPECT_EQ(rig::capture::load((dir() / "leap.rigcap").string()).samples.size(), 100u);
  // A restart 1.1 s short of the counter's period, the clock 1 ms on: it passed as a 1100-sample
  // gap, every later sample 1.1 s late (a review). 0.2 s of lost frames with the clock stamping
  // them 1 ms apart (a receiver's burst) is still a gap.
  for (const uint64_t lost : {1100u, 200u}) {
    std::ostringstream near;
    t = t0;
    const uint64_t top = (uint64_t{1} << 24) - lost;
    for (uint64_t k = top - 100; k < top; ++k, t += 1e-3) log_sample(near, t, k);
    for (uint64_t k = 0; k < 100; ++k, t += 1e-3) log_sample(near, t, k);
    const std::string name = "near" + std::to_string(lost);
    if (lost == 1100) {
      EXPECT_EQ(import(name, near.str()), 2) << slurp(dir() / (name + ".out"));
      EXPECT_NE(slurp(dir() / (name + ".err")).find(name + ".log:201: the stream's counter leapt 1101 samples (1.101 s at "
                                                    "1000 Hz) where the log's clock moved 0.000"),
                std::string::npos)
          << slurp(dir() / (name + ".err"));
      EXPECT_EQ(rig::capture::load((dir() / (name + ".rigcap")).string()).samples.size(), 100u);
    } else {
      EXPECT_EQ(import(name, near.str()), 0) << slurp(dir() / (name + ".err"));
      EXPECT_EQ(rig::capture::load((dir() / (name + ".rigcap")).string()).samples.size(), 200u);
    }
  }
  // The same restart after the stream paused 0.5 s (the leap 1.1 s): it passed under "four times
  // the clock plus 2 s" (a re-test); a 1.1 s gap the clock shows as 1.1 s is still a gap.
  for (const double pause : {0.5, 1.1}) {
    std::ostringstream paused;
    t = t0;
    const uint64_t top = (uint64_t{1} << 24) - 1100;
    for (uint64_t k = top - 100; k < top; ++k, t += 1e-3) log_sample(paused, t, k);
    t += pause - 1e-3;
    for (uint64_t k = 0; k < 100; ++k, t += 1e-3) log_sample(paused, t, k);  // 1100 samples ahead (it wraps)
    const std::string name = pause == 0.5 ? "paused-restart" : "paused-gap";
    EXPECT_EQ(import(name, paused.str()), pause == 0.5 ? 2 : 0) << slurp(dir() / (name + ".err"));
    if (pause == 0.5) {
      EXPECT_NE(slurp(dir() / (name + ".err")).find("(the DUT restarted? or its rate is not 1000 Hz: --rate)"),
                std::string::npos)
          << slurp(dir() / (name + ".err"));
    }
  }

  std::ostringstream first;
  first << log_line(t0, encode(StreamHalf{Channel::X, 5000, 0, 0.5f}));  // one part, then a power cycle
  for (uint64_t k = 0; k < 100; ++k) log_sample(first, t0 + 0.5 + static_cast<double>(k) * 1e-3, k);
  EXPECT_EQ(import("first", first.str()), 2);
  EXPECT_NE(slurp(dir() / "first.err").find("first.log:2: the stream's counter went back from 5000 to 0"),
            std::string::npos) << slurp(dir() / "first.err");
  EXPECT_NE(slurp(dir() / "first.err").find("not written: no sample before it; import the rest into another capture "
                                            "with --from-line 2"),
            std::string::npos) << slurp(dir() / "first.err");
  EXPECT_FALSE(fs::exists(dir() / "first.rigcap"));

  std::ostringstream mid;
  for (uint64_t k = 1000; k < 1104; ++k) log_sample(mid, t0 + static_cast<double>(k - 1000) * 1e-3, k, k != 1100);
  ASSERT_EQ(import("mid", mid.str()), 0) << slurp(dir() / "mid.err");
  EXPECT_NE(slurp(dir() / "mid.out").find("gap at seq 1100: 1 samples"), std::string::npos) << slurp(dir() / "mid.out");
  EXPECT_EQ(slurp(dir() / "mid.out").find("incomplete sample(s) at the end"), std::string::npos) << slurp(dir() / "mid.out");

  std::ostringstream half;
  half << log_line(t0, encode(StreamHalf{Channel::Y, 999, 0, 0.5f}));  // the log begins after 999's X
  for (uint64_t k = 1000; k < 1100; ++k) log_sample(half, t0 + static_cast<double>(k - 1000) * 1e-3, k);
  ASSERT_EQ(import("half", half.str()), 0) << slurp(dir() / "half.err");
  EXPECT_NE(slurp(dir() / "half.out").find("gaps 0 (0 samples lost)"), std::string::npos) << slurp(dir() / "half.out");
  const auto c = rig::capture::load((dir() / "half.rigcap").string());
  ASSERT_EQ(c.samples.size(), 100u);
  EXPECT_EQ(c.samples.front().seq, 1000u);
  EXPECT_EQ(c.samples.front().status & rig::sample_status::kGapBefore, 0u);
}

// The layout held to the frames (an integrator's review: each of these imported with exit 0).
// The log's clock against the capture's rate: a 500 Hz log imported as the rig protocol's
// 1000 Hz (every tau off by 2), and a counter written little-endian where the DBC says
// big-endian (hundreds of thousands of samples "lost" in seconds), are refused and not written;
// the right --rate imports the same log. A value its DBC range excludes, or not finite (a float
// written big-endian where the DBC says little-endian), is counted, the first named, exit 2,
// the capture kept as decoded.
TEST(CaptureImport, TheLogsClockAndTheDbcsRangesHoldTheLayoutToTheFrames) {
  std::ostringstream slow;
  double t = 1732255200.0;
  for (uint64_t k = 0; k < 2000; ++k, t += 2e-3) {
    slow << log_line(t, encode(StreamHalf{Channel::X, static_cast<uint32_t>(k), 0, x_of(k)}));
    slow << log_line(t + 1e-4, encode(StreamHalf{Channel::Y, static_cast<uint32_t>(k), 0, -x_of(k)}));
  }
  std::ofstream(dir() / "slow.log") << slow.str();
  std::ofstream(dir() / "hw-slow.toml") << "[dut]\ncan = \"vcan0\"\n";
  const std::string slow_args = "capture import " + (dir() / "slow.log").string() + " --hardware " +
                                (dir() / "hw-slow.toml").string() + " --out " + (dir() / "slow.rigcap").string();
  EXPECT_EQ(run_rig(slow_args, "slow"), 2) << slurp(dir() / "slow.out");
  const std::string why = slurp(dir() / "slow.err");
  EXPECT_NE(why.find("slow.log: the log's clock gives 499.96"), std::string::npos) << why;
  EXPECT_NE(why.find(" Hz (lines 1 to 4000), the capture's rate would be 1000 Hz (the hardware file's or the protocol's)"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("every tau would be off by a factor of 2."), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(dir() / "slow.rigcap")) << "not written";
  // Its summary names no capture it did not write (it read "slow.log -> slow.rigcap: 2000 samples").
  EXPECT_NE(slurp(dir() / "slow.out").find("slow.log: 2000 samples from 4000 stream frames"), std::string::npos)
      << slurp(dir() / "slow.out");
  EXPECT_EQ(slurp(dir() / "slow.out").find(" -> "), std::string::npos) << slurp(dir() / "slow.out");
  ASSERT_EQ(run_rig(slow_args + " --rate 500", "slow500"), 0) << slurp(dir() / "slow500.err");
  EXPECT_NE(slurp(dir() / "slow500.out").find("slow.log -> " + (dir() / "slow.rigcap").string() + ": 2000 samples"),
            std::string::npos)
      << slurp(dir() / "slow500.out");
  EXPECT_NE(slurp(dir() / "slow500.out").find("the log's clock: 2000 samples (0 lost among them) in 3.998"),
            std::string::npos)
      << slurp(dir() / "slow500.out");
  EXPECT_EQ(rig::capture::load((dir() / "slow.rigcap").string()).header.rate_hz, 500.0);
  // A logger that stamps in 50 ms bursts (1.2 s at 1 kHz: 4 % off end to end), and a clock that
  // stepped back (said, samples placed by counter), are no wrong rate (a code review).
  std::ostringstream bursts, stepped;
  for (uint64_t k = 0; k < 1200; ++k) {
    const double tb = 1732255200.0 + 0.05 * static_cast<double>(k / 50 + 1);
    const double ts = 1732255200.0 + 1e-3 * static_cast<double>(k) - (k >= 600 ? 5.0 : 0.0);
    for (const auto& [o, at] : {std::pair{&bursts, tb}, std::pair{&stepped, ts}}) {
      *o << log_line(at, encode(StreamHalf{Channel::X, static_cast<uint32_t>(k), 0, x_of(k)}));
      *o << log_line(at, encode(StreamHalf{Channel::Y, static_cast<uint32_t>(k), 0, -x_of(k)}));
    }
  }
  for (const auto& [name, text] : {std::pair{"bursts", bursts.str()}, std::pair{"stepped", stepped.str()}}) {
    std::ofstream(dir() / (std::string(name) + ".log")) << text;
    EXPECT_EQ(run_rig("capture import " + (dir() / (std::string(name) + ".log")).string() + " --hardware " +
                          (dir() / "hw-slow.toml").string() + " --out " + (dir() / (std::string(name) + ".rigcap")).string(),
                      name),
              0)
        << name << ": " << slurp(dir() / (std::string(name) + ".err"));
  }

  // ACC_XY (tests/data/dbc/dut-layouts.dbc, 2000 Hz), its counter written in the other byte order.
  const Dbc db = Dbc::parse_file(std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/dut-layouts.dbc");
  const DbcMessage* m = db.find("ACC_XY");
  ASSERT_NE(m, nullptr);
  std::ostringstream swapped;
  t = 1732255200.0;
  for (uint64_t k = 0; k < 4000; ++k, t += 5e-4) {
    CanFrame f;
    f.id = m->id;
    f.extended = true;
    f.len = 8;
    std::span<uint8_t> d(f.data.data(), 8);
    dbc_insert_raw(d, 0, 16, false, k % 65536);  // the DBC: 7|16@0+, big-endian
    dbc_insert_raw(d, 23, 24, true, dbc_raw_of(*m->signal("x"), x_of(k)));
    dbc_insert_raw(d, 47, 24, true, dbc_raw_of(*m->signal("y"), -x_of(k)));
    swapped << log_line(t, f);
  }
  std::ofstream(dir() / "swapped.log") << swapped.str();
  std::ofstream(dir() / "hw-swapped.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << RIG_SOURCE_DIR
                                           << "/tests/data/dbc/dut-layouts.dbc\"\n[dut.stream]\ncounter = \"ACC_XY.cnt\"\n"
                                              "x = \"ACC_XY.x\"\ny = \"ACC_XY.y\"\nrate_hz = 2000\n";
  EXPECT_EQ(run_rig("capture import " + (dir() / "swapped.log").string() + " --hardware " +
                        (dir() / "hw-swapped.toml").string() + " --out " + (dir() / "swapped.rigcap").string(),
                    "swapped"),
            2)
      << slurp(dir() / "swapped.out");
  EXPECT_FALSE(fs::exists(dir() / "swapped.rigcap")) << slurp(dir() / "swapped.err");
  EXPECT_NE(slurp(dir() / "swapped.out").find("  ... 3979 more gaps\n"), std::string::npos)
      << "every gap counted, not the list's 1000: " << slurp(dir() / "swapped.out");
  EXPECT_NE(slurp(dir() / "swapped.err").find("Check [dut.stream] rate_hz (or give --rate with the DUT's rate) and the "
                                              "counter signal's byte order"),
            std::string::npos)
      << slurp(dir() / "swapped.err");

  // A float in mg with a range, written big-endian where the DBC says little-endian.
  std::ofstream(dir() / "float.dbc") << "VERSION \"\"\n\nNS_ :\n\tSIG_VALTYPE_\n\nBS_:\n\nBU_: DUT RIG\n\n"
                                        "BO_ 2566870300 ACC_F: 6 DUT\n"
                                        " SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" RIG\n"
                                        " SG_ x_mg : 16|32@1- (1,0) [-20000|20000] \"mg\" RIG\n\n"
                                        "SIG_VALTYPE_ 2566870300 x_mg : 1;\n";
  // 1500 samples at 1 kHz of a DBC id (extended) of `len` bytes: a 16-bit counter at bit 0, then
  // `value(k)` (its raw bits) from bit 16, both little-endian.
  auto write_log = [](const std::string& name, uint32_t dbc_id, uint8_t len, int bits,
                      const std::function<uint64_t(uint64_t)>& value) {
    std::ostringstream log;
    double at = 1732255200.0;
    for (uint64_t k = 0; k < 1500; ++k, at += 1e-3) {
      CanFrame f;
      f.id = dbc_id & 0x1FFFFFFFu;
      f.extended = true;
      f.len = len;
      std::span<uint8_t> d(f.data.data(), len);
      dbc_insert_raw(d, 0, 16, false, k);
      dbc_insert_raw(d, 16, bits, false, value(k));
      log << log_line(at, f);
    }
    std::ofstream(dir() / name) << log.str();
  };
  write_log("float.log", 2566870300u, 6, 32, [](uint64_t k) -> uint64_t {
    if (k == 700) return 0x7FC00000u;  // one NaN, in the DBC's own byte order
    const float mg = x_of(k) * 1000.0f;
    uint32_t bits = 0;
    std::memcpy(&bits, &mg, 4);
    return __builtin_bswap32(bits);
  });
  std::ofstream(dir() / "hw-float.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << (dir() / "float.dbc").string()
                                         << "\"\n[dut.stream]\ncounter = \"ACC_F.cnt\"\nx = \"ACC_F.x_mg\"\n";
  EXPECT_EQ(run_rig("capture import " + (dir() / "float.log").string() + " --hardware " + (dir() / "hw-float.toml").string() +
                        " --out " + (dir() / "float.rigcap").string(),
                    "float"),
            2)
      << slurp(dir() / "float.out") << slurp(dir() / "float.err");
  const std::string err = slurp(dir() / "float.err");
  EXPECT_NE(err.find(" decoded value(s) outside their signal's DBC range, 1 of them not finite (the first at "),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("float.log:4: ACC_F.x_mg = -428398656 mg, its DBC range [-20000|20000] mg; "), std::string::npos)
      << "in the signal's unit, against its range: " << err;
  EXPECT_NE(err.find("; the first not finite at " + (dir() / "float.log").string() + ":701: ACC_F.x_mg = nan mg"),
            std::string::npos)
      << "the NaN located, not only the first value outside the range: " << err;
  EXPECT_NE(err.find("the capture holds them as decoded (a value not finite fails every analysis: exit 2)"),
            std::string::npos)
      << err;
  EXPECT_TRUE(fs::exists(dir() / "float.rigcap")) << "kept as decoded";
  // Outside the range alone (a DUT past its DBC's declared range, or a wrong layout): said, exit 0.
  std::ofstream(dir() / "tight.dbc") << "VERSION \"\"\n\nNS_ :\n\nBS_:\n\nBU_: DUT RIG\n\n"
                                        "BO_ 2566870301 ACC_T: 4 DUT\n"
                                        " SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" RIG\n"
                                        " SG_ x_mg : 16|16@1- (1,0) [-40|40] \"mg\" RIG\n";
  write_log("tight.log", 2566870301u, 4, 16, [](uint64_t k) -> uint64_t {
    return static_cast<uint16_t>(static_cast<int16_t>(std::lround(x_of(k) * 1000.0f)));
  });
  std::ofstream(dir() / "hw-tight.toml") << "[dut]\ncan = \"vcan0\"\ndbc = \"" << (dir() / "tight.dbc").string()
                                         << "\"\n[dut.stream]\ncounter = \"ACC_T.cnt\"\nx = \"ACC_T.x_mg\"\n";
  EXPECT_EQ(run_rig("capture import " + (dir() / "tight.log").string() + " --hardware " + (dir() / "hw-tight.toml").string() +
                        " --out " + (dir() / "tight.rigcap").string(),
                    "tight"),
            0)
      << slurp(dir() / "tight.err");
  EXPECT_NE(slurp(dir() / "tight.err").find("decoded value(s) outside their signal's DBC range, 0 of them not finite"),
            std::string::npos)
      << slurp(dir() / "tight.err");
}
