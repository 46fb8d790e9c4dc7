// candump log reading (firmware_link/candump_log): the log format of `candump -l`/`-L`,
// cansend's bare form and candump's screen format, on files written by can-utils itself
// (tests/data/candump: asc2log and log2long), and unreadable lines reported with a reason.
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "firmware_link/candump_log.hpp"
#include "firmware_link/protocol.hpp"

using namespace rig::link;

namespace {

std::vector<CandumpLogReader::Entry> read_all(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  CandumpLogReader r(in);
  std::vector<CandumpLogReader::Entry> out;
  for (CandumpLogReader::Entry e; r.next(e);) out.push_back(e);
  return out;
}

}  // namespace

TEST(CandumpLog, BothFormatsOfOneSessionReadTheSameFrames) {
  const auto l = read_all(RIG_CANDUMP_DIR "/session-l.log");
  const auto screen = read_all(RIG_CANDUMP_DIR "/session-screen.txt");
  ASSERT_EQ(l.size(), 10u);
  ASSERT_EQ(screen.size(), 10u);
  for (std::size_t i = 0; i < l.size(); ++i) {
    ASSERT_EQ(l[i].parsed.kind, LogLineKind::Frame) << "line " << l[i].line << ": " << l[i].parsed.problem;
    ASSERT_EQ(screen[i].parsed.kind, LogLineKind::Frame) << "line " << screen[i].line << ": " << screen[i].parsed.problem;
    EXPECT_EQ(l[i].line, i + 1);
    EXPECT_EQ(l[i].parsed.frame.frame, screen[i].parsed.frame.frame) << "line " << i + 1;
    EXPECT_DOUBLE_EQ(l[i].parsed.frame.t_s, screen[i].parsed.frame.t_s);
    EXPECT_EQ(l[i].parsed.frame.iface, "can0");
  }
  EXPECT_EQ(l[2].parsed.frame.frame, encode(StreamHalf{Channel::X, 0x123456, 5, 1.0f}));
  EXPECT_EQ(l[0].parsed.frame.frame, encode(Command{Op::GetSerial, 7, 1, 2, 0x11223344u}));
  EXPECT_EQ(l[7].parsed.frame.frame.len, 4) << "the short frame is read as it is; decoding decides";
}

TEST(CandumpLog, LogFormatVariants) {
  // candump -l as can-utils 2020.11 writes it (no direction flag), and with asc2log's flag.
  for (const char* s : {"(1700000000.123456) vcan0 100#563412050000803F", "(1700000000.123456) vcan0 100#563412050000803F R"}) {
    const LogLine l = read_candump_line(s);
    ASSERT_EQ(l.kind, LogLineKind::Frame) << s << ": " << l.problem;
    EXPECT_DOUBLE_EQ(l.frame.t_s, 1700000000.123456);
    EXPECT_EQ(l.frame.iface, "vcan0");
    EXPECT_EQ(l.frame.frame, encode(StreamHalf{Channel::X, 0x123456, 5, 1.0f}));
  }
  auto bare = read_candump_line("010#30.07.01.02.44.33.22.11");  // cansend's separators
  ASSERT_EQ(bare.kind, LogLineKind::Frame) << bare.problem;
  EXPECT_EQ(bare.frame.frame, encode(Command{Op::GetSerial, 7, 1, 2, 0x11223344u}));
  auto rtr = read_candump_line("(2.5) can0 010#R");
  ASSERT_EQ(rtr.kind, LogLineKind::Frame);
  EXPECT_TRUE(rtr.frame.frame.rtr);
  auto err = read_candump_line("(1.0) can0 20000040#0000000000000000");
  ASSERT_EQ(err.kind, LogLineKind::Frame);
  EXPECT_TRUE(err.frame.frame.error);
  EXPECT_EQ(err.frame.frame.id, 0x40u);
  auto ext = read_candump_line("(1.0) can0 18FF0001#01");
  ASSERT_EQ(ext.kind, LogLineKind::Frame);
  EXPECT_TRUE(ext.frame.frame.extended);
  EXPECT_EQ(ext.frame.frame.id, 0x18FF0001u);
}

TEST(CandumpLog, ScreenFormatVariants) {
  auto plain = read_candump_line("  vcan0  101   [8]  56 34 12 05 00 00 80 3F");  // plain `candump vcan0`
  ASSERT_EQ(plain.kind, LogLineKind::Frame) << plain.problem;
  EXPECT_EQ(plain.frame.frame, encode(StreamHalf{Channel::Y, 0x123456, 5, 1.0f}));
  EXPECT_EQ(plain.frame.t_s, 0.0);
  auto rel = read_candump_line(" (000.001000)  vcan0  010   [0]  remote request");  // -td
  ASSERT_EQ(rel.kind, LogLineKind::Frame) << rel.problem;
  EXPECT_TRUE(rel.frame.frame.rtr);
  EXPECT_DOUBLE_EQ(rel.frame.t_s, 0.001);
  auto ef = read_candump_line("  can0  20000004   [8]  00 04 00 00 00 00 00 00   ERRORFRAME");
  ASSERT_EQ(ef.kind, LogLineKind::Frame) << ef.problem;
  EXPECT_TRUE(ef.frame.frame.error);
}

TEST(CandumpLog, EmptyLinesAndUnreadableLinesWithTheirReason) {
  EXPECT_EQ(read_candump_line("").kind, LogLineKind::Empty);
  EXPECT_EQ(read_candump_line("   # a comment").kind, LogLineKind::Empty);
  const std::pair<const char*, const char*> bad[] = {
      {"101#0102030", "odd number of hex digits"},
      {"(1.0) can0 100#563412050000803F11", "more than 8 data bytes"},
      {"(1.0) can0 100##1563412", "CAN FD"},
      {"  can0  100  [12]  00 11 22 33 44 55 66 77 88 99 AA BB", "CAN FD"},
      {"  can0  100   [8]  56 34 12", "only 3 data byte(s)"},
      {"(1.0) can0 1000#00", "not a CAN identifier"},
      {"(1.0 can0 100#00", "bad timestamp"},
      {"(abc) can0 100#00", "bad timestamp"},
      {"(1.0) can0 100#00 trailing words", "text after the frame"},
      {"hello world", "not a candump frame line"},
      {"(1.0) can0 800#00", "standard identifier out of range"},
      {"(1.0) can0 CFFFFFFF#00", "extended identifier out of range"},  // found by fuzz_candump
  };
  for (const auto& [line, why] : bad) {
    const LogLine l = read_candump_line(line);
    EXPECT_EQ(l.kind, LogLineKind::Unreadable) << line;
    EXPECT_NE(l.problem.find(why), std::string::npos) << line << ": " << l.problem;
  }
  std::istringstream in("# header\n\n(1.0) can0 100#00\nnot a frame\n");
  CandumpLogReader r(in);
  CandumpLogReader::Entry e;
  ASSERT_TRUE(r.next(e));
  EXPECT_EQ(e.line, 3u);
  EXPECT_EQ(e.parsed.kind, LogLineKind::Frame);
  ASSERT_TRUE(r.next(e));
  EXPECT_EQ(e.line, 4u);
  EXPECT_EQ(e.parsed.kind, LogLineKind::Unreadable);
  EXPECT_FALSE(r.next(e));
}
