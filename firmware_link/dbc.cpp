#include "firmware_link/dbc.hpp"

// GCC 12 with -fsanitize=address reports a false -Wmaybe-uninitialized inside
// <regex>'s std::function members (libstdc++ internals, not this file's code).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "rig/core/errors.hpp"

namespace rig::link {

namespace {

[[noreturn]] void fail(const std::string& src, int line, const std::string& msg) {
  throw ConfigError(src + ":" + std::to_string(line) + ": " + msg);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

// Numbers of a DBC line: decimal, in range of the field they fill, or an error naming the
// line (a DBC from another tool can carry any digits the grammar allows).
template <class T>
T integer(const std::string& src, int line, const std::string& text, const char* what) {
  T v{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size())
    fail(src, line, std::string(what) + " '" + text + "' is not a whole number in range");
  return v;
}

double num(const std::string& src, int line, const std::string& text, const char* what) {
  const double v = std::strtod(text.c_str(), nullptr);
  if (!std::isfinite(v)) fail(src, line, std::string(what) + " '" + text + "' is not a finite number");
  return v;
}

}  // namespace

const DbcSignal* DbcMessage::signal(const std::string& n) const {
  for (const auto& s : signals)
    if (s.name == n) return &s;
  return nullptr;
}

Dbc Dbc::parse_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open DBC file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path);
}

Dbc Dbc::parse(const std::string& text, const std::string& src) {
  static const std::regex bo_re(R"(^BO_\s+(\d+)\s+(\w+)\s*:\s*(\d+)\s+(\w+)\s*$)");
  static const std::regex sg_re(
      R"(^SG_\s+(\w+)\s*(M|m\d+)?\s*:\s*(\d+)\|(\d+)@([01])([+-])\s*\(\s*([-+0-9.eE]+)\s*,\s*([-+0-9.eE]+)\s*\)\s*\[\s*([-+0-9.eE]+)\s*\|\s*([-+0-9.eE]+)\s*\]\s*"([^"]*)\"\s*(.*)$)");
  static const std::regex valtype_re(R"(^SIG_VALTYPE_\s+(\d+)\s+(\w+)\s*:\s*([0-3])\s*;\s*$)");
  static const std::regex val_re(R"(^VAL_\s+(\d+)\s+(\w+)\s+(.*);\s*$)");
  static const std::regex pair_re(R"((-?\d+)\s+"([^"]*)\")");

  Dbc dbc;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  DbcMessage* cur = nullptr;
  auto find_sig = [&](const std::string& id_s, const std::string& name) -> DbcSignal& {
    const auto id = integer<uint32_t>(src, line, id_s, "message id");
    for (auto& m : dbc.messages_)
      if (m.id == id)
        for (auto& s : m.signals)
          if (s.name == name) return s;
    fail(src, line, "signal '" + name + "' of message " + id_s + " is not defined");
  };
  while (std::getline(in, raw)) {
    ++line;
    const std::string l = trim(raw);
    std::smatch m;
    if (l.rfind("BO_ ", 0) == 0) {
      if (!std::regex_match(l, m, bo_re)) fail(src, line, "malformed BO_ line");
      DbcMessage msg;
      msg.id = integer<uint32_t>(src, line, m[1], "message id");
      msg.name = m[2];
      msg.dlc = integer<int>(src, line, m[3], "DLC");
      msg.sender = m[4];
      if (msg.id & 0x80000000u) fail(src, line, "extended-id message " + msg.name + " is not supported");
      if (msg.dlc > 8) fail(src, line, "message " + msg.name + " has DLC " + std::to_string(msg.dlc) + " (> 8)");
      if (dbc.find(msg.id)) fail(src, line, "message id " + std::to_string(msg.id) + " defined twice");
      dbc.messages_.push_back(msg);
      cur = &dbc.messages_.back();
    } else if (l.rfind("SG_ ", 0) == 0) {
      if (!cur) fail(src, line, "SG_ outside a message");
      if (!std::regex_match(l, m, sg_re)) fail(src, line, "malformed SG_ line");
      DbcSignal s;
      s.name = m[1];
      const std::string mux = m[2];
      s.multiplexor = mux == "M";
      if (!mux.empty() && mux[0] == 'm') s.mux_value = integer<int>(src, line, mux.substr(1), "multiplexer value");
      s.start = integer<int>(src, line, m[3], "start bit");
      s.length = integer<int>(src, line, m[4], "bit length");
      if (m[5] == "0") fail(src, line, "signal " + s.name + ": Motorola (big-endian) byte order is not supported");
      s.is_signed = m[6] == "-";
      s.factor = num(src, line, m[7], "factor");
      s.offset = num(src, line, m[8], "offset");
      s.min = num(src, line, m[9], "minimum");
      s.max = num(src, line, m[10], "maximum");
      s.unit = m[11];
      s.line = line;
      if (s.length < 1 || s.length > 64 || s.start > 64 || s.start + s.length > cur->dlc * 8)
        fail(src, line, "signal " + s.name + " (" + std::to_string(s.start) + "|" + std::to_string(s.length) +
                            ") does not fit the message's " + std::to_string(cur->dlc) + " bytes");
      if (cur->signal(s.name)) fail(src, line, "signal " + s.name + " defined twice in " + cur->name);
      cur->signals.push_back(s);
    } else if (l.rfind("SIG_VALTYPE_ ", 0) == 0) {
      if (!std::regex_match(l, m, valtype_re)) fail(src, line, "malformed SIG_VALTYPE_ line");
      DbcSignal& s = find_sig(m[1], m[2]);
      s.value_type = integer<int>(src, line, m[3], "value type");
      if ((s.value_type == 1 && s.length != 32) || (s.value_type == 2 && s.length != 64))
        fail(src, line, "signal " + s.name + ": float type needs 32 (or 64) bits, has " + std::to_string(s.length));
    } else if (l.rfind("VAL_ ", 0) == 0) {
      if (!std::regex_match(l, m, val_re)) fail(src, line, "malformed VAL_ line");
      DbcSignal& s = find_sig(m[1], m[2]);
      const std::string pairs = m[3];
      for (std::sregex_iterator it(pairs.begin(), pairs.end(), pair_re), end; it != end; ++it)
        s.value_names[integer<long long>(src, line, (*it)[1], "value")] = (*it)[2];
    } else if (l.empty()) {
      cur = nullptr;  // a blank line ends a message block
    }
  }
  if (dbc.messages_.empty()) fail(src, line, "no messages (BO_) defined");
  return dbc;
}

const DbcMessage* Dbc::find(uint32_t id) const {
  for (const auto& m : messages_)
    if (m.id == id) return &m;
  return nullptr;
}

uint64_t dbc_extract_raw(const CanFrame& f, int start, int length) {
  uint64_t word = 0;
  for (int i = 0; i < 8; ++i) word |= static_cast<uint64_t>(f.data[static_cast<std::size_t>(i)]) << (8 * i);
  const uint64_t mask = length >= 64 ? ~uint64_t{0} : ((uint64_t{1} << length) - 1);
  return (word >> start) & mask;
}

double dbc_physical(const DbcSignal& s, const CanFrame& f) {
  const uint64_t raw = dbc_extract_raw(f, s.start, s.length);
  double v;
  if (s.value_type == 1) {
    v = std::bit_cast<float>(static_cast<uint32_t>(raw));
  } else if (s.value_type == 2) {
    v = std::bit_cast<double>(raw);
  } else if (s.is_signed && s.length < 64 && (raw >> (s.length - 1)) & 1) {
    v = static_cast<double>(static_cast<int64_t>(raw) - (int64_t{1} << s.length));
  } else {
    v = s.is_signed ? static_cast<double>(static_cast<int64_t>(raw)) : static_cast<double>(raw);
  }
  return v * s.factor + s.offset;
}

std::optional<std::vector<DecodedSignal>> Dbc::decode(const CanFrame& f, std::string* error) const {
  const DbcMessage* m = f.extended || f.error ? nullptr : find(f.id);
  if (!m) return std::nullopt;
  if (f.len != m->dlc) {
    if (error) *error = m->name + ": length " + std::to_string(f.len) + ", DBC says " + std::to_string(m->dlc);
    return std::nullopt;
  }
  std::optional<int64_t> mux;
  for (const auto& s : m->signals)
    if (s.multiplexor) mux = static_cast<int64_t>(dbc_extract_raw(f, s.start, s.length));
  std::vector<DecodedSignal> out;
  for (const auto& s : m->signals) {
    if (s.mux_value && (!mux || *mux != *s.mux_value)) continue;
    DecodedSignal d{s.name, dbc_physical(s, f), s.unit, {}};
    if (auto it = s.value_names.find(static_cast<int64_t>(d.value)); it != s.value_names.end()) d.value_name = it->second;
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace rig::link
