// Reading candump logs (can-utils) line by line, in the formats a technician brings:
//   log format, `candump -l` files and `candump -L` output:
//       (1700000000.123456) vcan0 100#563412050000803F          (optionally a trailing R/T
//       (1700000000.123456) can0 100#56341205 R                  direction, as asc2log writes)
//   cansend's bare form:                100#563412050000803F
//   screen format, plain `candump` (optionally -ta/-td/-tz timestamps, -a ASCII column):
//       (1700000000.123456)  vcan0  100   [8]  56 34 12 05 00 00 80 3F
//         vcan0  010   [0]  remote request
// CAN FD frames in both: `ID##F<data>` in the log format (F: one hex digit of flags, bit 0 BRS),
// a two-digit length `[12]` .. `[64]` on screen.
// A line that is none of these (a truncated last line, text) is reported with the
// reason, not silently dropped, so a decoder can count and name it.
#pragma once
#include <cstddef>
#include <istream>
#include <optional>
#include <string>
#include <string_view>

#include "firmware_link/protocol.hpp"

namespace rig::link {

// One frame of a log: time (seconds, absolute or relative as logged; 0 when the line has
// none), interface ("" when the line has none), the frame.
struct LoggedFrame {
  double t_s = 0;
  bool timed = false;  // the line had a time stamp (candump's screen output without -t has none: t_s 0)
  std::string iface;
  CanFdFrame any;  // the frame as logged, classic or CAN FD (any.fd): what DBC decoding takes
  CanFrame frame;  // the same frame in classic form, when !any.fd (else empty): the rig codec's
};

enum class LogLineKind { Empty, Frame, Unreadable };  // Empty: blank or a `#` comment
struct LogLine {
  LogLineKind kind = LogLineKind::Empty;
  LoggedFrame frame;    // when kind == Frame
  std::string problem;  // when kind == Unreadable: why, naming the offending token
};
LogLine read_candump_line(std::string_view line);

// The frame of one line, or nullopt (empty or unreadable line).
std::optional<LoggedFrame> parse_candump_line(const std::string& line);

// One line of a log, at most kMaxLogLine characters kept: a longer one (no candump line is: a
// 64-byte FD frame on screen with its ASCII column is under 400) is read to its end without
// growing (`rig dut decode /dev/zero` grew by 140 MB a second, a review) and returned cut to
// that length, `too_long` set. False at the end of the stream, as std::getline.
inline constexpr std::size_t kMaxLogLine = 4096;
bool read_log_line(std::istream& in, std::string& line, bool& too_long);
// What is said of such a line.
std::string too_long_problem();

// A stream of log lines with their line numbers; empty lines are skipped.
class CandumpLogReader {
 public:
  explicit CandumpLogReader(std::istream& in) : in_(in) {}
  struct Entry {
    std::size_t line = 0;  // 1-based
    LogLine parsed;        // Frame or Unreadable
  };
  // The next non-empty line; false at the end of the stream.
  bool next(Entry& e);

 private:
  std::istream& in_;
  std::size_t line_ = 0;
};

}  // namespace rig::link
