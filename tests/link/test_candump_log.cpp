// candump log reading (firmware_link/candump_log): the log format of `candump -l`/`-L`,
// cansend's bare form and candump's screen format, on files written by can-utils itself
// (tests/data/candump: asc2log and log2long), and unreadable lines reported with a reason.
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include <ctime>

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
  // -tA: the host's local date and time (it was refused as a bad timestamp, a review); a date
  // that does not exist or a negative field is refused, not moved to another day (a code review).
  auto abs = read_candump_line(" (2023-11-14 22:13:20.000700)  vcan0  101   [8]  56 34 12 05 00 00 80 3F");
  ASSERT_EQ(abs.kind, LogLineKind::Frame) << abs.problem;
  std::tm tm{};
  tm.tm_year = 123, tm.tm_mon = 10, tm.tm_mday = 14, tm.tm_hour = 22, tm.tm_min = 13, tm.tm_sec = 20, tm.tm_isdst = -1;
  EXPECT_DOUBLE_EQ(abs.frame.t_s, static_cast<double>(std::mktime(&tm)) + 0.0007);
  for (const char* bad : {" (2023-02-31 22:13:20.000700)  vcan0  101   [8]  56 34 12 05 00 00 80 3F",
                          " (2023-11-14 -1:13:20.000700)  vcan0  101   [8]  56 34 12 05 00 00 80 3F",
                          " (2023-11-14 22:-3:20.000700)  vcan0  101   [8]  56 34 12 05 00 00 80 3F"}) {
    const auto l = read_candump_line(bad);
    EXPECT_EQ(l.kind, LogLineKind::Unreadable) << bad;
    EXPECT_NE(l.problem.find("bad timestamp"), std::string::npos) << l.problem;
  }
}

TEST(CandumpLog, EmptyLinesAndUnreadableLinesWithTheirReason) {
  EXPECT_EQ(read_candump_line("").kind, LogLineKind::Empty);
  EXPECT_EQ(read_candump_line("   # a comment").kind, LogLineKind::Empty);
  const std::pair<const char*, const char*> bad[] = {
      {"101#0102030", "odd number of hex digits"},
      {"(1.0) can0 100#563412050000803F11", "more than 8 data bytes"},
      {"(1.0) can0 100##1001122334455667788", "CAN FD frame of 9 data bytes"},
      {"(1.0) can0 100##", "without its flags digit"},
      {"  can0  100  [13]  00 11 22 33 44 55 66 77 88 99 AA BB CC", "for a CAN FD frame"},
      {"  can0  100  [9]  00 11 22 33 44 55 66 77 88", "for a classic frame"},
      {"  can0  100   [8]  56 34 12", "only 3 data byte(s)"},
      {"(1.0) can0 1000#00", "not a CAN identifier"},
      {"(1.0 can0 100#00", "bad timestamp"},
      {"(abc) can0 100#00", "bad timestamp"},
      {"(170.1E4456) can0 101#56341204", "bad timestamp"},  // overflows to inf (fuzz_candump)
      {"(nan) can0 101#56341204", "bad timestamp"},
      {"(-5.000000) can0 101#56341204", "bad timestamp"},  // candump writes no sign, no exponent
      {"(+5.000000) can0 101#56341204", "bad timestamp"},
      {"(1e9) can0 101#56341204", "bad timestamp"},
      {"(1.0) can0 100#00 trailing words", "text after the frame"},
      {"hello world", "not a candump frame line (expected IFACE ID#DATA or IFACE ID [N] BYTES): 'hello world'"},
      // A CRLF log's \r and other bytes that are not printable are shown, not sent to the terminal.
      {"hello\x01 w\xB5rld\r", "BYTES): 'hello\\x01 w\\xB5rld'"},
      {"(1.0) can0 800#00", "standard identifier out of range"},
      {"(1.0) can0 CFFFFFFF#00", "extended identifier out of range"},  // found by fuzz_candump
      // An identifier's control bytes too (a review: 0x1E reached the terminal as it was).
      {"(1.0) can0 1\x1e""0#00", "not a CAN identifier (3 or 8 hex digits): '1\\x1E0'"},
  };
  const std::string zs(100, 'z');
  EXPECT_NE(read_candump_line(zs).problem.find("BYTES): '" + std::string(57, 'z') + "...'"), std::string::npos);
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

// Issue 15, 3: CAN FD frames as candump logs them: `ID##F<data>` (-l, -L; F the flags digit,
// bit 0 the bit-rate switch) and a two-digit length on screen (as can-utils' log2long prints).
TEST(CandumpLog, CanFdFramesInLogAndScreenFormats) {
  std::string data;
  for (int i = 0; i < 64; ++i) data += "0123456789ABCDEF"[i % 16], data += "0123456789ABCDEF"[(i * 7) % 16];
  const LogLine l = read_candump_line("(1732255200.000000) vcan0 18FF2000##1" + data);
  ASSERT_EQ(l.kind, LogLineKind::Frame) << l.problem;
  EXPECT_TRUE(l.frame.any.fd);
  EXPECT_TRUE(l.frame.any.brs);
  EXPECT_TRUE(l.frame.any.extended);
  EXPECT_EQ(l.frame.any.id, 0x18FF2000u);
  ASSERT_EQ(l.frame.any.len, 64);
  EXPECT_EQ(l.frame.any.data[63], 0xF9);
  EXPECT_EQ(l.frame.frame.len, 0) << "no classic view of an FD frame";
  const LogLine short_fd = read_candump_line("(1.5) can0 123##0AABB R");
  ASSERT_EQ(short_fd.kind, LogLineKind::Frame) << short_fd.problem;
  EXPECT_TRUE(short_fd.frame.any.fd);
  EXPECT_FALSE(short_fd.frame.any.brs);
  EXPECT_EQ(short_fd.frame.any.len, 2);
  std::string bytes;
  for (int i = 0; i < 12; ++i) bytes += " 5A";
  const LogLine scr = read_candump_line("(1732255200.007000)  vcan0       123  [12] " + bytes);
  ASSERT_EQ(scr.kind, LogLineKind::Frame) << scr.problem;
  EXPECT_TRUE(scr.frame.any.fd);
  EXPECT_EQ(scr.frame.any.len, 12);
  EXPECT_EQ(scr.frame.any.data[11], 0x5A);
  const LogLine fd8 = read_candump_line("  vcan0  123  [08]  01 02 03 04 05 06 07 08");
  ASSERT_EQ(fd8.kind, LogLineKind::Frame) << fd8.problem;
  EXPECT_TRUE(fd8.frame.any.fd) << "[08] is an FD frame of 8 bytes";
  const LogLine classic = read_candump_line("  vcan0  123   [8]  01 02 03 04 05 06 07 08");
  ASSERT_EQ(classic.kind, LogLineKind::Frame);
  EXPECT_FALSE(classic.frame.any.fd);
  EXPECT_EQ(classic.frame.frame.len, 8);
  EXPECT_EQ(classic.frame.frame.data[7], 8);
}
