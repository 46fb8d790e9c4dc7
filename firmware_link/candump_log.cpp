#include "firmware_link/candump_log.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <vector>

#include "rig/core/escape.hpp"

namespace rig::link {

namespace {

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    const std::size_t start = i;
    while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    if (i > start) out.push_back(s.substr(start, i - start));
  }
  return out;
}

bool all_hex(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

uint8_t hex_byte(std::string_view two) { return static_cast<uint8_t>(std::strtoul(std::string(two).c_str(), nullptr, 16)); }

// Shown as rig shows any value from a file: control and non-UTF-8 bytes as \xNN (a review: an
// identifier's bytes reached the terminal raw, a newline and 0x1E among them).
std::string quoted(std::string_view s) { return "'" + shown_text(s) + "'"; }

// candump prints identifiers as 3 (standard) or 8 (extended) hex digits; an extended id
// with bit 29 set is an error frame (CAN_ERR_FLAG), its class bits below.
bool set_id(std::string_view id, CanFdFrame& f, std::string& problem) {
  if (!all_hex(id) || (id.size() != 3 && id.size() != 8)) {
    problem = "not a CAN identifier (3 or 8 hex digits): " + quoted(id);
    return false;
  }
  f.extended = id.size() == 8;
  f.id = static_cast<uint32_t>(std::strtoul(std::string(id).c_str(), nullptr, 16));
  if (!f.extended && f.id > 0x7FF) {
    problem = "standard identifier out of range: " + quoted(id);
    return false;
  }
  // Bits 30 and 31 are SocketCAN's RTR and EFF flags, which candump never prints in the id:
  // such an id is damage, not a 29-bit identifier (found by tests/fuzz/fuzz_candump.cpp).
  if (f.extended && (f.id & 0xC0000000u)) {
    problem = "extended identifier out of range (29 bits, or 2xxxxxxx for an error frame): " + quoted(id);
    return false;
  }
  if (f.extended && (f.id & 0x20000000u)) {
    f.error = true;
    f.extended = false;
    f.id &= 0x1FFFFFFFu;
  }
  return true;
}

// "ID#DATA", "ID#R" (remote request), "ID##FDATA" (CAN FD: F is one hex digit of flags,
// bit 0 bit-rate switch, bit 1 error state indicator; then 0..64 data bytes of a valid FD length).
bool log_frame(std::string_view tok, CanFdFrame& f, std::string& problem) {
  const auto hash = tok.find('#');
  if (!set_id(tok.substr(0, hash), f, problem)) return false;
  std::string_view data = tok.substr(hash + 1);
  if (!data.empty() && data[0] == '#') {
    if (data.size() < 2 || !std::isxdigit(static_cast<unsigned char>(data[1]))) {
      problem = "CAN FD frame " + quoted(tok) + " without its flags digit (ID##F<data>)";
      return false;
    }
    f.fd = true;
    f.brs = (std::strtoul(std::string(data.substr(1, 1)).c_str(), nullptr, 16) & 1u) != 0;
    data = data.substr(2);
  }
  if (!f.fd && !data.empty() && (data[0] == 'R' || data[0] == 'r')) {
    f.rtr = true;
    return true;
  }
  std::string hex;
  for (char c : data)
    if (c != '.') hex += c;  // cansend allows 11.22.33
  if (!hex.empty() && !all_hex(hex)) {
    problem = "data is not hex: " + quoted(data);
    return false;
  }
  if (hex.size() % 2) {
    problem = "odd number of hex digits in the data: " + quoted(data) + " (a truncated line?)";
    return false;
  }
  const std::size_t bytes = hex.size() / 2;
  if (!f.fd && bytes > 8) {
    problem = "more than 8 data bytes in a classic frame: " + quoted(data);
    return false;
  }
  if (f.fd && (bytes > 64 || canfd_round_up(static_cast<int>(bytes)) != static_cast<int>(bytes))) {
    problem = "CAN FD frame of " + std::to_string(bytes) + " data bytes (valid: 0..8, 12, 16, 20, 24, 32, 48, 64): " +
              quoted(tok);
    return false;
  }
  f.len = static_cast<uint8_t>(hex.size() / 2);
  for (std::size_t i = 0; i < f.len; ++i) f.data[i] = hex_byte(std::string_view(hex).substr(2 * i, 2));
  return true;
}

// "ID [N] B0 B1 ..." with optional trailers: "remote request", "ERRORFRAME", an -a ASCII column.
// A CAN FD frame's length is printed with two digits ("[08]", "[64]"), a classic one's with one.
bool screen_frame(const std::vector<std::string_view>& t, std::size_t i, CanFdFrame& f, std::string& problem) {
  if (!set_id(t[i], f, problem)) return false;
  const std::string_view dlc = t[i + 1];
  const std::string_view n = dlc.substr(1, dlc.size() - 2);
  if (n.empty() || n.size() > 2 || !std::isdigit(static_cast<unsigned char>(n[0])) ||
      !std::isdigit(static_cast<unsigned char>(n.back()))) {
    problem = "bad length field " + quoted(dlc);
    return false;
  }
  const unsigned len = static_cast<unsigned>(std::strtoul(std::string(n).c_str(), nullptr, 10));
  f.fd = n.size() == 2;
  if ((!f.fd && len > 8) || (f.fd && (len > 64 || canfd_round_up(static_cast<int>(len)) != static_cast<int>(len)))) {
    problem = "bad length " + quoted(dlc) + (f.fd ? " for a CAN FD frame" : " for a classic frame");
    return false;
  }
  std::size_t k = i + 2;
  if (!f.fd && k < t.size() && t[k] == "remote") {
    f.rtr = true;
    f.len = static_cast<uint8_t>(len);
    return true;
  }
  f.len = static_cast<uint8_t>(len);
  for (unsigned b = 0; b < len; ++b, ++k) {
    if (k >= t.size()) {
      problem = "length " + quoted(dlc) + " but only " + std::to_string(b) + " data byte(s) (a truncated line?)";
      return false;
    }
    if (t[k].size() != 2 || !all_hex(t[k])) {
      problem = "data byte " + std::to_string(b) + " is not two hex digits: " + quoted(t[k]);
      return false;
    }
    f.data[b] = hex_byte(t[k]);
  }
  for (; k < t.size(); ++k)
    if (t[k] != "ERRORFRAME" && t[k].front() != '\'') {
      problem = "unexpected text after the data: " + quoted(t[k]);
      return false;
    }
  return true;
}

}  // namespace

LogLine read_candump_line(std::string_view line) {
  LogLine out;
  const auto t = split(line);
  if (t.empty() || t[0].front() == '#') return out;
  out.kind = LogLineKind::Unreadable;
  std::size_t i = 0;
  LoggedFrame& lf = out.frame;
  CanFdFrame& any = lf.any;
  if (t[0].front() == '(' && t[0].back() != ')' && t.size() > 1 && t[1].back() == ')') {
    // candump -tA: "(2023-11-14 22:13:20.000700)", the local date and time as candump's host
    // had them; read in this host's time zone (the same host, as a bench log usually is).
    const std::string day(t[0].substr(1)), clock(t[1].substr(0, t[1].size() - 1));
    auto refused = [&] {  // the stamp as written, both of its tokens
      return "bad timestamp " + quoted(line.substr(0, static_cast<std::size_t>(t[1].data() + t[1].size() - line.data())));
    };
    int y = 0, mo = 0, d = 0, h = 0, mi = 0, n1 = 0, n2 = 0;
    double sec = -1;
    const bool read = std::sscanf(day.c_str(), "%4d-%2d-%2d%n", &y, &mo, &d, &n1) == 3 &&
                      n1 == static_cast<int>(day.size()) &&
                      std::sscanf(clock.c_str(), "%2d:%2d:%lf%n", &h, &mi, &sec, &n2) == 3 &&
                      n2 == static_cast<int>(clock.size());
    if (!read || y < 1970 || mo < 1 || mo > 12 || d < 1 || d > 31 || h < 0 || h > 23 || mi < 0 || mi > 59 ||
        !(sec >= 0 && sec < 61) || day[0] == '-' || clock[0] == '-' || clock[3] == '-') {
      out.problem = refused();
      return out;
    }
    std::tm tm{};
    tm.tm_year = y - 1900;
    tm.tm_mon = mo - 1;
    tm.tm_mday = d;
    tm.tm_hour = h;
    tm.tm_min = mi;
    tm.tm_isdst = -1;
    const std::time_t base = std::mktime(&tm);
    // mktime normalises 2023-02-31 to March 3rd: a date it had to move is no date.
    if (base == static_cast<std::time_t>(-1) || tm.tm_mday != d || tm.tm_mon != mo - 1) {
      out.problem = refused();
      return out;
    }
    lf.t_s = static_cast<double>(base) + sec;
    lf.timed = true;
    i = 2;
  } else if (t[0].front() == '(') {
    if (t[0].back() != ')') {
      out.problem = "bad timestamp " + quoted(t[0]);
      return out;
    }
    const std::string ts(t[0].substr(1, t[0].size() - 2));
    char* end = nullptr;
    lf.t_s = std::strtod(ts.c_str(), &end);
    // A time stamp that overflows to inf (or reads as nan) is no time: found by fuzz_candump,
    // whose invariant is that every frame read has a finite time. candump writes digits and a
    // point ("%lu.%06lu"; -td, -tz alike): a sign, a hex or exponent form is no stamp of its
    // ("(-5.000000)" was read as a relative clock, carried in session 34's note).
    const bool digits = !ts.empty() && std::isdigit(static_cast<unsigned char>(ts.front())) &&
                        ts.find_first_not_of("0123456789.") == std::string::npos;
    if (!digits || *end != '\0' || !std::isfinite(lf.t_s)) {
      out.problem = "bad timestamp " + quoted(t[0]);
      return out;
    }
    lf.timed = true;
    i = 1;
  }
  const std::size_t rest = t.size() - i;
  bool ok = false;
  if (rest >= 1 && t[i].find('#') != std::string_view::npos) {  // bare ID#DATA
    ok = log_frame(t[i], any, out.problem);
    if (ok && rest > 1) {
      out.problem = "text after the frame: " + quoted(t[i + 1]);
      ok = false;
    }
  } else if (rest >= 2 && t[i + 1].find('#') != std::string_view::npos) {  // IFACE ID#DATA [R|T]
    lf.iface = std::string(t[i]);
    ok = log_frame(t[i + 1], any, out.problem);
    if (ok && rest > 2 && !(rest == 3 && (t[i + 2] == "R" || t[i + 2] == "T"))) {
      out.problem = "text after the frame: " + quoted(t[i + 2]);
      ok = false;
    }
  } else if (rest >= 3 && t[i + 2].front() == '[' && t[i + 2].back() == ']') {  // IFACE ID [N] bytes
    lf.iface = std::string(t[i]);
    ok = screen_frame(t, i + 1, any, out.problem);
  } else {
    // The line itself, cut at 57 bytes, as shown_text shows text (a byte a terminal acts on as
    // \xNN: a CRLF log's \r moved the cursor, binary bytes reached the terminal): the message
    // must show what was there (a review).
    std::string_view text = line.substr(line.find_first_not_of(" \t"));
    while (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    out.problem = "not a candump frame line (expected IFACE ID#DATA or IFACE ID [N] BYTES): " +
                  quoted(text.size() > 57 ? shown_text(text.substr(0, 57)) + "..." : shown_text(text));
  }
  if (ok) {
    out.kind = LogLineKind::Frame;
    if (!any.fd) {  // the classic view the rig protocol's codec takes
      lf.frame.id = any.id;
      lf.frame.extended = any.extended;
      lf.frame.rtr = any.rtr;
      lf.frame.error = any.error;
      lf.frame.len = any.len;
      std::copy_n(any.data.begin(), 8, lf.frame.data.begin());
    }
  }
  return out;
}

std::optional<LoggedFrame> parse_candump_line(const std::string& line) {
  LogLine l = read_candump_line(line);
  if (l.kind != LogLineKind::Frame) return std::nullopt;
  return std::move(l.frame);
}

std::string too_long_problem() {
  return "a line longer than " + std::to_string(kMaxLogLine) + " characters: not a candump log line";
}

bool read_log_line(std::istream& in, std::string& line, bool& too_long) {
  line.clear();
  too_long = false;
  std::streambuf* sb = in.rdbuf();
  bool any = false;
  for (;;) {
    const int c = sb->sbumpc();
    if (c == std::char_traits<char>::eof()) {
      in.setstate(std::ios::eofbit);
      if (!any) in.setstate(std::ios::failbit);
      return any;
    }
    any = true;
    if (c == '\n') return true;
    if (line.size() < kMaxLogLine) line.push_back(static_cast<char>(c));
    else too_long = true;
  }
}

bool CandumpLogReader::next(Entry& e) {
  std::string text;
  bool too_long = false;
  while (read_log_line(in_, text, too_long)) {
    ++line_;
    if (too_long) {
      e.line = line_;
      e.parsed = LogLine{};
      e.parsed.kind = LogLineKind::Unreadable;
      e.parsed.problem = too_long_problem();
      return true;
    }
    LogLine l = read_candump_line(text);
    if (l.kind == LogLineKind::Empty) continue;
    e.line = line_;
    e.parsed = std::move(l);
    return true;
  }
  return false;
}

}  // namespace rig::link
