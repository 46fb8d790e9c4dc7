#include "firmware_link/candump_log.hpp"

#include <cctype>
#include <cstdlib>
#include <vector>

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

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

// candump prints identifiers as 3 (standard) or 8 (extended) hex digits; an extended id
// with bit 29 set is an error frame (CAN_ERR_FLAG), its class bits below.
bool set_id(std::string_view id, CanFrame& f, std::string& problem) {
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

// "ID#DATA", "ID#R" (remote request), "ID##..." (CAN FD: not this protocol's).
bool log_frame(std::string_view tok, CanFrame& f, std::string& problem) {
  const auto hash = tok.find('#');
  if (!set_id(tok.substr(0, hash), f, problem)) return false;
  std::string_view data = tok.substr(hash + 1);
  if (!data.empty() && data[0] == '#') {
    problem = "CAN FD frame " + quoted(tok) + " (the DUT's protocol is classic CAN)";
    return false;
  }
  if (!data.empty() && (data[0] == 'R' || data[0] == 'r')) {
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
  if (hex.size() > 16) {
    problem = "more than 8 data bytes: " + quoted(data);
    return false;
  }
  f.len = static_cast<uint8_t>(hex.size() / 2);
  for (std::size_t i = 0; i < f.len; ++i) f.data[i] = hex_byte(std::string_view(hex).substr(2 * i, 2));
  return true;
}

// "ID [N] B0 B1 ..." with optional trailers: "remote request", "ERRORFRAME", an -a ASCII column.
bool screen_frame(const std::vector<std::string_view>& t, std::size_t i, CanFrame& f, std::string& problem) {
  if (!set_id(t[i], f, problem)) return false;
  const std::string_view dlc = t[i + 1];
  const std::string_view n = dlc.substr(1, dlc.size() - 2);
  if (n.empty() || n.size() > 2 || !std::isdigit(static_cast<unsigned char>(n[0])) ||
      !std::isdigit(static_cast<unsigned char>(n.back()))) {
    problem = "bad length field " + quoted(dlc);
    return false;
  }
  const unsigned len = static_cast<unsigned>(std::strtoul(std::string(n).c_str(), nullptr, 10));
  if (len > 8 || n.size() == 2) {
    problem = "CAN FD frame of length " + quoted(dlc) + " (the DUT's protocol is classic CAN)";
    return false;
  }
  std::size_t k = i + 2;
  if (k < t.size() && t[k] == "remote") {
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
  if (t[0].front() == '(') {
    if (t[0].back() != ')') {
      out.problem = "bad timestamp " + quoted(t[0]);
      return out;
    }
    const std::string ts(t[0].substr(1, t[0].size() - 2));
    char* end = nullptr;
    lf.t_s = std::strtod(ts.c_str(), &end);
    if (ts.empty() || *end != '\0') {
      out.problem = "bad timestamp " + quoted(t[0]);
      return out;
    }
    i = 1;
  }
  const std::size_t rest = t.size() - i;
  bool ok = false;
  if (rest >= 1 && t[i].find('#') != std::string_view::npos) {  // bare ID#DATA
    ok = log_frame(t[i], lf.frame, out.problem);
    if (ok && rest > 1) {
      out.problem = "text after the frame: " + quoted(t[i + 1]);
      ok = false;
    }
  } else if (rest >= 2 && t[i + 1].find('#') != std::string_view::npos) {  // IFACE ID#DATA [R|T]
    lf.iface = std::string(t[i]);
    ok = log_frame(t[i + 1], lf.frame, out.problem);
    if (ok && rest > 2 && !(rest == 3 && (t[i + 2] == "R" || t[i + 2] == "T"))) {
      out.problem = "text after the frame: " + quoted(t[i + 2]);
      ok = false;
    }
  } else if (rest >= 3 && t[i + 2].front() == '[' && t[i + 2].back() == ']') {  // IFACE ID [N] bytes
    lf.iface = std::string(t[i]);
    ok = screen_frame(t, i + 1, lf.frame, out.problem);
  } else {
    out.problem = "not a candump frame line (expected IFACE ID#DATA or IFACE ID [N] BYTES)";
  }
  if (ok) out.kind = LogLineKind::Frame;
  return out;
}

std::optional<LoggedFrame> parse_candump_line(const std::string& line) {
  LogLine l = read_candump_line(line);
  if (l.kind != LogLineKind::Frame) return std::nullopt;
  return std::move(l.frame);
}

bool CandumpLogReader::next(Entry& e) {
  std::string text;
  while (std::getline(in_, text)) {
    ++line_;
    LogLine l = read_candump_line(text);
    if (l.kind == LogLineKind::Empty) continue;
    e.line = line_;
    e.parsed = std::move(l);
    return true;
  }
  return false;
}

}  // namespace rig::link
