#include "firmware_link/dbc.hpp"

// GCC 12 with -fsanitize=address reports a false -Wmaybe-uninitialized inside
// <regex>'s std::function members (libstdc++ internals, not this file's code).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <algorithm>
#include <array>
#include <bit>
#include <bitset>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/number_text.hpp"

namespace rig::link {

namespace {

[[noreturn]] void fail(const std::string& src, int line, const std::string& msg) {
  throw ConfigError(src + ":" + std::to_string(line) + ": " + msg);
}

// Numbers of a DBC line: decimal, in range of the field they fill, or an error naming the
// line (a DBC from another tool can carry any digits the grammar allows).
template <class T>
T integer(const std::string& src, int line, const std::string& text, const char* what) {
  T v{};
  const char* b = text.data();
  if (!text.empty() && text[0] == '+') ++b;  // from_chars takes no '+'
  const auto [end, ec] = std::from_chars(b, text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || b == text.data() + text.size())
    fail(src, line, std::string(what) + " '" + text + "' is not a whole number in range");
  return v;
}

double num(const std::string& src, int line, const std::string& text, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size())
    fail(src, line, std::string(what) + " '" + text + "' is not a number");
  if (!std::isfinite(v)) fail(src, line, std::string(what) + " '" + text + "' is not a finite number");
  return v;
}

// ---- tokens ------------------------------------------------------------------------

enum class Tok { Ident, Number, String, Punct };
struct Token {
  Tok kind;
  std::string text;  // strings unescaped, without quotes
  int line;
};

bool ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }
bool digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

std::vector<Token> tokenize(const std::string& t, const std::string& src) {
  std::vector<Token> out;
  // About one token per 4 characters in DBC text: reserved once instead of grown by copying
  // (the growth was a fifth of the tokenizer's time in tests/fuzz/fuzz_dbc.cpp's profile).
  out.reserve(t.size() / 4 + 8);
  int line = 1;
  // A UTF-8 byte-order mark, as Windows editors save a file, is not text: skipped (it was
  // "1: unexpected character 0xEF", a review).
  std::size_t i = t.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  const std::size_t n = t.size();
  while (i < n) {
    const char c = t[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++i;
    } else if (c == '/' && i + 1 < n && t[i + 1] == '/') {  // a comment some tools accept
      while (i < n && t[i] != '\n') ++i;
    } else if (c == '"') {
      const int at = line;
      std::string s;
      ++i;
      for (;;) {
        if (i >= n) fail(src, at, "string not closed by '\"'");
        if (t[i] == '\\' && i + 1 < n && (t[i + 1] == '"' || t[i + 1] == '\\')) {
          s += t[i + 1];
          i += 2;
          continue;
        }
        if (t[i] == '"') break;
        if (t[i] == '\n') ++line;
        s += t[i++];
      }
      ++i;
      out.push_back({Tok::String, std::move(s), at});
    } else if (ident_start(c)) {
      const std::size_t b = i;
      while (i < n && ident_char(t[i])) ++i;
      out.push_back({Tok::Ident, t.substr(b, i - b), line});
    } else if (digit(c) || ((c == '-' || c == '+' || c == '.') && i + 1 < n && (digit(t[i + 1]) || t[i + 1] == '.'))) {
      // [+-]digits[.digits][e[+-]digits]; "@1+" / "@1-" end the number before the sign
      const std::size_t b = i;
      if (c == '-' || c == '+') ++i;
      while (i < n && (digit(t[i]) || t[i] == '.')) ++i;
      if (i < n && (t[i] == 'e' || t[i] == 'E') &&
          ((i + 1 < n && digit(t[i + 1])) || (i + 2 < n && (t[i + 1] == '+' || t[i + 1] == '-') && digit(t[i + 2])))) {
        i += 2;
        while (i < n && digit(t[i])) ++i;
      }
      if (i < n && (ident_char(t[i]) || t[i] == '.'))
        fail(src, line, "malformed number '" + t.substr(b, i - b + 1) + "'");
      out.push_back({Tok::Number, t.substr(b, i - b), line});
    } else if (std::string_view(":;,|@()[]+-").find(c) != std::string_view::npos) {
      out.push_back({Tok::Punct, std::string(1, c), line});
      ++i;
    } else {
      char buf[16];
      std::snprintf(buf, sizeof buf, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
      fail(src, line, std::string("unexpected character ") + (std::isprint(static_cast<unsigned char>(c)) ? "'" + std::string(1, c) + "'" : std::string(buf)));
    }
  }
  return out;
}

const std::set<std::string, std::less<>>& keywords() {
  static const std::set<std::string, std::less<>> k{
      "VERSION", "NS_", "NS_DESC_", "BS_", "BU_", "BO_", "SG_", "CM_", "VAL_TABLE_", "VAL_", "BA_DEF_",
      "BA_DEF_DEF_", "BA_", "BA_DEF_REL_", "BA_REL_", "BA_DEF_DEF_REL_", "BA_DEF_SGTYPE_", "BA_SGTYPE_",
      "SIG_GROUP_", "SIG_VALTYPE_", "SIGTYPE_VALTYPE_", "BO_TX_BU_", "EV_", "ENVVAR_DATA_", "EV_DATA_",
      "SGTYPE_", "SGTYPE_VAL_", "SIG_TYPE_REF_", "SG_MUL_VAL_", "CAT_DEF_", "CAT_", "FILTER", "BU_SG_REL_",
      "BU_EV_REL_", "BU_BO_REL_"};
  return k;
}

std::string describe(const Token& t) {
  switch (t.kind) {
    case Tok::String: return "string \"" + t.text + "\"";
    case Tok::Number: return "number " + t.text;
    default: return "'" + t.text + "'";
  }
}

// A statement's tokens, read front to back; errors name the offending token's line.
class Cursor {
 public:
  Cursor(const std::vector<Token>& toks, std::size_t b, std::size_t e, const std::string& src, int line)
      : t_(toks), b_(b), i_(b), e_(e), src_(src), line_(line) {}
  bool done() const { return i_ >= e_; }
  bool at_punct(char c) const { return !done() && t_[i_].kind == Tok::Punct && t_[i_].text[0] == c; }
  bool at(Tok k) const { return !done() && t_[i_].kind == k; }
  int line() const { return done() ? last_line() : t_[i_].line; }
  [[noreturn]] void error(const std::string& msg) const { fail(src_, line(), msg); }
  const Token& take(Tok k, const char* what) {
    if (done()) fail(src_, last_line(), std::string("expected ") + what + ", found the end of the statement");
    if (t_[i_].kind != k) error(std::string("expected ") + what + ", found " + describe(t_[i_]));
    return t_[i_++];
  }
  std::string ident(const char* what) { return take(Tok::Ident, what).text; }
  std::string str(const char* what) { return take(Tok::String, what).text; }
  std::string number(const char* what) { return take(Tok::Number, what).text; }
  void punct(char c) {
    const std::string what = std::string("'") + c + "'";
    if (!at_punct(c)) {
      if (done()) fail(src_, last_line(), "expected " + what + ", found the end of the statement");
      error("expected " + what + ", found " + describe(t_[i_]));
    }
    ++i_;
  }
  // Numbers carry their sign ("-40", "1e-06"); the field name goes into the error.
  template <class T>
  T whole(const char* what) {
    const int l = line();
    return integer<T>(src_, l, number(what), what);
  }
  double real(const char* what) {
    const int l = line();
    return num(src_, l, number(what), what);
  }
  void end() const {
    if (!done()) error("unexpected " + describe(t_[i_]) + " at the end of the statement");
  }

 private:
  // The line of the statement's last token read (or its keyword's): where it ended.
  int last_line() const { return i_ > b_ ? t_[std::min(i_, e_) - 1].line : line_; }
  const std::vector<Token>& t_;
  std::size_t b_, i_, e_;
  const std::string& src_;
  int line_;
};

// A `length`-bit two's-complement value as int64 (shifts, so no signed overflow at 63 bits).
int64_t sign_extend(uint64_t raw, int length) {
  const int sh = 64 - length;
  return static_cast<int64_t>(raw << sh) >> sh;
}

bool same_line_end(const std::vector<Token>& t, std::size_t i, int line) { return i >= t.size() || t[i].line != line; }

// Bit positions of a signal, most significant first (Motorola) or least significant first
// (Intel), in the DBC's numbering (byte * 8 + bit in byte).
template <class F>
void for_each_bit(int start, int length, bool big_endian, F&& f) {
  int pos = start;
  for (int k = 0; k < length; ++k) {
    f(k, pos);
    if (big_endian)
      pos = pos % 8 == 0 ? pos + 15 : pos - 1;
    else
      ++pos;
  }
}

}  // namespace

const DbcSignal* DbcMessage::signal(const std::string& n) const {
  for (const auto& s : signals)
    if (s.name == n) return &s;
  return nullptr;
}

bool dbc_signal_fits(const DbcSignal& s, int bytes) {
  if (s.length < 1 || s.length > 64 || s.start < 0 || s.start >= bytes * 8) return false;
  bool ok = true;
  for_each_bit(s.start, s.length, s.big_endian, [&](int, int pos) { ok = ok && pos >= 0 && pos < bytes * 8; });
  return ok;
}

std::bitset<512> dbc_signal_bits(const DbcSignal& s, uint64_t raw_bits) {
  std::array<uint8_t, 64> payload{};
  dbc_insert_raw(payload, s.start, s.length, s.big_endian, raw_bits);  // the codec's own bit order
  std::bitset<512> bits;
  for (std::size_t i = 0; i < 512; ++i)
    if ((payload[i / 8] >> (i % 8)) & 1u) bits.set(i);
  return bits;
}

bool dbc_same_frame(const DbcSignal& a, const DbcSignal& b) {
  return !(a.mux_value && b.mux_value && *a.mux_value != *b.mux_value);
}

// ---- the parser ----------------------------------------------------------------------

class DbcParser {
 public:
  DbcParser(const std::string& text, const std::string& src) : src_(src), t_(tokenize(text, src)) {}

  Dbc run() {
    std::size_t i = 0;
    while (i < t_.size()) {
      const Token& k = t_[i];
      if (k.kind != Tok::Ident || !keywords().count(k.text))
        fail(src_, k.line, "expected a DBC keyword (BO_, SG_, CM_, ...), found " + describe(k));
      const std::string& kw = k.text;
      if (kw == "NS_") {
        i = skip_ns(i);
        continue;
      }
      if (kw == "VERSION" || kw == "BS_" || kw == "BU_" || kw == "BO_" || kw == "SG_") {
        std::size_t e = i + 1;  // line statements end with their line
        while (!same_line_end(t_, e, k.line)) ++e;
        Cursor c(t_, i + 1, e, src_, k.line);
        if (kw == "VERSION") {
          db_.version_ = c.str("the version string");
          c.end();
        } else if (kw == "BU_") {
          c.punct(':');
          while (!c.done()) db_.nodes_.push_back(c.ident("a node name"));
        } else if (kw == "BO_") {
          message(c, k.line);
        } else if (kw == "SG_") {
          signal(c, k.line);
        }  // BS_: the bit timing section is obsolete and carries nothing the rig uses
        if (kw != "SG_") in_message_ = kw == "BO_";
        i = e;
        continue;
      }
      in_message_ = false;
      // Statements ending in ';', possibly over several lines.
      std::size_t e = i + 1;
      static const std::set<std::string, std::less<>> inner{"BU_", "BO_", "SG_", "EV_", "BU_SG_REL_", "BU_EV_REL_",
                                                             "BU_BO_REL_"};
      while (e < t_.size() && !(t_[e].kind == Tok::Punct && t_[e].text == ";")) {
        // A statement keyword opening a line: the previous statement lacks its ';'.
        if (t_[e].kind == Tok::Ident && t_[e].line != t_[e - 1].line && keywords().count(t_[e].text) &&
            !inner.count(t_[e].text))
          fail(src_, k.line, kw + " statement not terminated by ';'");
        ++e;
      }
      if (e >= t_.size()) fail(src_, k.line, kw + " statement not terminated by ';'");
      Cursor c(t_, i + 1, e, src_, k.line);
      statement(kw, c);
      i = e + 1;
    }
    if (db_.messages_.empty()) fail(src_, t_.empty() ? 1 : t_.back().line, "no messages (BO_) defined");
    // Checked once every statement is read (a multiplexed signal may precede its multiplexor, a
    // SIG_VALTYPE_ comes after both): a signal multiplexed in a message with no multiplexor was
    // never decoded, a float multiplexor selected pages by its bits (a review).
    for (const auto& m : db_.messages_) {
      const auto mux = std::find_if(m.signals.begin(), m.signals.end(), [](const DbcSignal& s) { return s.multiplexor; });
      const bool has_mux = mux != m.signals.end();
      for (const auto& s : m.signals) {
        if (s.mux_value && !has_mux)
          fail(src_, s.line, "signal " + s.name + " is multiplexed (m" + std::to_string(*s.mux_value) + ") but message " +
                                 m.name + " has no multiplexor (M)");
        // A page the multiplexor's bits cannot carry is never selected: its signals never arrive
        // (a review: m9 under a 2-bit multiplexor was accepted, and a log read as nothing).
        if (s.mux_value && has_mux && mux->length < 63 && *s.mux_value >= (int64_t{1} << mux->length))
          fail(src_, s.line, "signal " + s.name + " is on multiplexer page " + std::to_string(*s.mux_value) +
                                 ", which multiplexor " + mux->name + " of " + m.name + " (" +
                                 std::to_string(mux->length) + " bits: pages 0.." +
                                 std::to_string((int64_t{1} << mux->length) - 1) + ") cannot carry");
        if (s.multiplexor && s.value_type != 0)
          fail(src_, s.line, "multiplexor " + s.name + " of " + m.name + " is a float (SIG_VALTYPE_): it must be an integer");
      }
    }
    db_.source_ = src_;
    return std::move(db_);
  }

 private:
  std::size_t skip_ns(std::size_t i) {
    // "NS_ :" then the new symbols the file may use, one per line.
    const int l = t_[i].line;
    ++i;
    if (i < t_.size() && t_[i].kind == Tok::Punct && t_[i].text == ":" && t_[i].line == l) ++i;
    while (i < t_.size() && t_[i].kind == Tok::Ident && same_line_end(t_, i + 1, t_[i].line) &&
           (i == 0 || t_[i - 1].line != t_[i].line))
      ++i;
    return i;
  }

  void message(Cursor& c, int line) {
    DbcMessage msg;
    const uint32_t raw = c.whole<uint32_t>("message id");
    msg.name = c.ident("the message name");
    c.punct(':');
    msg.dlc = c.whole<int>("DLC");
    msg.sender = c.ident("the sending node");
    c.end();
    msg.line = line;
    msg.extended = (raw & 0x80000000u) != 0;
    msg.id = raw & 0x7FFFFFFFu;
    // Vector's pseudo-message holding signals not sent in any frame (id 0xC0000000).
    if (msg.extended && msg.id > 0x1FFFFFFFu) {
      if (msg.name != "VECTOR__INDEPENDENT_SIG_MSG")
        fail(src_, line, "message " + msg.name + ": extended id " + std::to_string(msg.id) + " exceeds 29 bits");
      pseudo_ids_.insert(raw);
      cur_ = &pseudo_;
      pseudo_ = DbcMessage{};
      pseudo_.dlc = 64;
      return;
    }
    if (!msg.extended && msg.id > 0x7FFu)
      fail(src_, line, "message " + msg.name + ": standard id " + std::to_string(msg.id) +
                           " exceeds 11 bits (an extended id has bit 31 set in BO_)");
    // A frame carries 0-8 bytes (classic CAN) or 12, 16, 20, 24, 32, 48 or 64 (CAN FD, ISO
    // 11898-1:2015): any other size no frame on the bus can have, and every frame was skipped as
    // "length 8, DBC says 9" (an integrator's review).
    // One message for every size outside them: "DLC -1 (> 64)" read wrong (a review).
    if (msg.dlc < 0 || canfd_round_up(msg.dlc) != msg.dlc)  // the frame lengths, as the candump reader checks them
      fail(src_, line, "message " + msg.name + ": length " + std::to_string(msg.dlc) +
                           " is not a CAN frame length (0-8 bytes, or 12, 16, 20, 24, 32, 48, 64 for CAN FD)");
    if (db_.find(msg.id, msg.extended)) fail(src_, line, "message id " + std::to_string(raw) + " defined twice");
    if (db_.find(msg.name)) fail(src_, line, "message name " + msg.name + " defined twice");
    db_.messages_.push_back(std::move(msg));
    cur_ = &db_.messages_.back();
  }

  void signal(Cursor& c, int line) {
    if (!in_message_ || !cur_) fail(src_, line, "SG_ outside a message");
    DbcSignal s;
    s.name = c.ident("the signal name");
    if (c.at(Tok::Ident)) {
      const std::string mux = c.ident("a multiplexer indicator");
      if (mux == "M") {
        s.multiplexor = true;
      } else if (mux.size() > 1 && mux[0] == 'm' && mux.back() == 'M') {
        c.error("signal " + s.name + ": extended multiplexing ('" + mux + "') is not supported");
      } else if (mux.size() > 1 && mux[0] == 'm') {
        s.mux_value = integer<int>(src_, line, mux.substr(1), "multiplexer value");
      } else {
        c.error("signal " + s.name + ": '" + mux + "' is not a multiplexer indicator (M or mN)");
      }
    }
    c.punct(':');
    s.start = c.whole<int>("start bit");
    c.punct('|');
    s.length = c.whole<int>("bit length");
    c.punct('@');
    const std::string order = c.number("byte order (0 or 1)");
    if (order != "0" && order != "1") c.error("byte order '" + order + "' is neither 0 (Motorola) nor 1 (Intel)");
    s.big_endian = order == "0";
    if (c.at_punct('+')) {
      c.punct('+');
    } else if (c.at_punct('-')) {
      c.punct('-');
      s.is_signed = true;
    } else {
      c.error("expected '+' or '-' after the byte order");
    }
    c.punct('(');
    s.factor = c.real("factor");
    c.punct(',');
    s.offset = c.real("offset");
    c.punct(')');
    c.punct('[');
    s.min = c.real("minimum");
    c.punct('|');
    s.max = c.real("maximum");
    c.punct(']');
    s.unit = c.str("the unit");
    while (!c.done()) {
      s.receivers.push_back(c.ident("a receiving node"));
      if (!c.done()) c.punct(',');
    }
    s.line = line;
    if (s.factor == 0) fail(src_, line, "signal " + s.name + ": factor 0");
    // [0|0] is "no range" as CAN tools write it; a minimum above the maximum is a slip, and the
    // import's range check was silently off for it (a review).
    if (s.min > s.max)
      fail(src_, line, "signal " + s.name + ": range [" + shortest_text(s.min) + "|" + shortest_text(s.max) +
                           "] has its minimum above its maximum");
    if (cur_ == &pseudo_) return;  // not part of any frame
    if (s.length == 0) fail(src_, line, "signal " + s.name + ": bit length 0 (a signal has 1 to 64 bits)");
    if (!dbc_signal_fits(s, cur_->dlc))
      fail(src_, line, "signal " + s.name + " (" + std::to_string(s.start) + "|" + std::to_string(s.length) + "@" +
                           order + ") does not fit the message's " + std::to_string(cur_->dlc) + " bytes");
    if (cur_->signal(s.name)) fail(src_, line, "signal " + s.name + " defined twice in " + cur_->name);
    if (s.multiplexor)
      for (const auto& o : cur_->signals)
        if (o.multiplexor) fail(src_, line, "message " + cur_->name + " has a second multiplexor " + s.name);
    cur_->signals.push_back(std::move(s));
  }

  // nullptr: a message of Vector's pseudo id (its signals are ignored).
  DbcMessage* message_ref(Cursor& c) {
    const int l = c.line();
    const uint32_t raw = c.whole<uint32_t>("message id");
    if (pseudo_ids_.count(raw)) return nullptr;
    for (auto& m : db_.messages_)
      if (m.id == (raw & 0x7FFFFFFFu) && m.extended == ((raw & 0x80000000u) != 0)) return &m;
    fail(src_, l, "message " + std::to_string(raw) + " is not defined");
  }
  DbcSignal* signal_ref(Cursor& c) {
    DbcMessage* m = message_ref(c);
    const int l = c.line();
    const std::string name = c.ident("a signal name");
    if (!m) return nullptr;
    for (auto& s : m->signals)
      if (s.name == name) return &s;
    fail(src_, l, "signal '" + name + "' of message " + m->name + " is not defined");
  }

  // Value of an attribute as text; ENUM indices become names.
  std::string attribute_value(Cursor& c, const std::string& attr) {
    auto d = db_.attr_defs_.find(attr);
    if (d == db_.attr_defs_.end()) c.error("attribute '" + attr + "' is not defined (BA_DEF_)");
    if (c.at(Tok::String)) return c.str("a value");
    const int l = c.line();
    const std::string v = c.number("a value");
    if (d->second.type == "ENUM") {
      const auto idx = integer<long long>(src_, l, v, "enum index");
      if (idx < 0 || idx >= static_cast<long long>(d->second.enum_values.size()))
        fail(src_, l, "attribute '" + attr + "': enum index " + v + " out of range");
      return d->second.enum_values[static_cast<std::size_t>(idx)];
    }
    (void)num(src_, l, v, "attribute value");
    return v;
  }

  void attribute_definition(Cursor& c, bool rel) {
    DbcAttributeDefinition d;
    if (c.at(Tok::Ident)) d.object = c.ident("an object type");
    static const std::set<std::string> objs{"BU_", "BO_", "SG_", "EV_"}, rel_objs{"BU_SG_REL_", "BU_EV_REL_", "BU_BO_REL_"};
    if (!d.object.empty() && !(rel ? rel_objs : objs).count(d.object))
      c.error("'" + d.object + "' is not an attribute object type");
    d.name = c.str("the attribute name");
    d.type = c.ident("the attribute type (INT, HEX, FLOAT, STRING, ENUM)");
    if (d.type == "INT" || d.type == "HEX" || d.type == "FLOAT") {
      c.real("minimum");
      c.real("maximum");
    } else if (d.type == "ENUM") {
      for (;;) {
        d.enum_values.push_back(c.str("an enum value"));
        if (c.done()) break;
        c.punct(',');
      }
    } else if (d.type != "STRING") {
      c.error("'" + d.type + "' is not an attribute type (INT, HEX, FLOAT, STRING, ENUM)");
    }
    c.end();
    db_.attr_defs_[d.name] = d;
  }

  void statement(const std::string& kw, Cursor& c) {
    if (kw == "CM_") {
      if (c.at(Tok::String)) {
        db_.comment_ = c.str("the comment");
      } else {
        const std::string obj = c.ident("BU_, BO_, SG_ or EV_");
        if (obj == "BU_") {
          const std::string node = c.ident("a node name");
          db_.node_comments_[node] = c.str("the comment");
        } else if (obj == "BO_") {
          DbcMessage* m = message_ref(c);
          const std::string text = c.str("the comment");
          if (m) m->comment = text;
        } else if (obj == "SG_") {
          DbcSignal* s = signal_ref(c);
          const std::string text = c.str("the comment");
          if (s) s->comment = text;
        } else if (obj == "EV_") {
          c.ident("an environment variable");
          c.str("the comment");
        } else {
          c.error("'" + obj + "' is not BU_, BO_, SG_ or EV_");
        }
      }
      c.end();
    } else if (kw == "VAL_TABLE_") {
      const std::string name = c.ident("the value table name");
      auto& table = db_.value_tables_[name];
      while (!c.done()) {
        const auto v = c.whole<long long>("value");
        table[v] = c.str("a value description");
      }
    } else if (kw == "VAL_") {
      if (c.at(Tok::Ident)) return;  // value descriptions of an environment variable
      DbcSignal* s = signal_ref(c);
      if (c.at(Tok::Ident)) {  // "VAL_ id signal TABLE_NAME;" refers to a VAL_TABLE_
        const int l = c.line();
        const std::string table = c.ident("a value table");
        auto it = db_.value_tables_.find(table);
        if (it == db_.value_tables_.end()) fail(src_, l, "value table '" + table + "' is not defined");
        if (s) s->value_names = it->second;
        c.end();
        return;
      }
      std::map<int64_t, std::string> names;
      while (!c.done()) {
        const auto v = c.whole<long long>("value");
        names[v] = c.str("a value description");
      }
      if (s) s->value_names = std::move(names);
    } else if (kw == "BA_DEF_") {
      attribute_definition(c, false);
    } else if (kw == "BA_DEF_REL_") {
      attribute_definition(c, true);
    } else if (kw == "BA_DEF_DEF_" || kw == "BA_DEF_DEF_REL_") {
      const std::string attr = c.str("the attribute name");
      auto d = db_.attr_defs_.find(attr);
      if (d == db_.attr_defs_.end()) c.error("attribute '" + attr + "' is not defined (BA_DEF_)");
      if (c.at(Tok::String))
        d->second.default_value = c.str("the default");
      else
        d->second.default_value = c.number("the default");
      c.end();
    } else if (kw == "BA_") {
      const std::string attr = c.str("the attribute name");
      DbcAttributes* on = &db_.attributes_;
      if (c.at(Tok::Ident)) {
        const std::string obj = c.ident("BU_, BO_, SG_ or EV_");
        if (obj == "BU_") {
          on = &db_.node_attributes_[c.ident("a node name")];
        } else if (obj == "BO_") {
          DbcMessage* m = message_ref(c);
          on = m ? &m->attributes : nullptr;
        } else if (obj == "SG_") {
          DbcSignal* s = signal_ref(c);
          on = s ? &s->attributes : nullptr;
        } else if (obj == "EV_") {
          c.ident("an environment variable");
          on = nullptr;
        } else {
          c.error("'" + obj + "' is not BU_, BO_, SG_ or EV_");
        }
      }
      const std::string v = attribute_value(c, attr);
      c.end();
      if (on) (*on)[attr] = v;
    } else if (kw == "SIG_VALTYPE_") {
      DbcSignal* s = signal_ref(c);
      if (c.at_punct(':')) c.punct(':');
      const int l = c.line();
      const int vt = c.whole<int>("value type");
      c.end();
      if (vt < 0 || vt > 2) fail(src_, l, "value type " + std::to_string(vt) + " is not 0, 1 (float) or 2 (double)");
      if (!s) return;
      if ((vt == 1 && s->length != 32) || (vt == 2 && s->length != 64))
        fail(src_, l, "signal " + s->name + ": float type needs 32 (or 64) bits, has " + std::to_string(s->length));
      s->value_type = vt;
    } else if (kw == "SIG_GROUP_") {
      DbcMessage* m = message_ref(c);
      DbcSignalGroup g;
      g.name = c.ident("the group name");
      g.repetitions = c.whole<int>("repetitions");
      c.punct(':');
      while (!c.done()) {
        const int l = c.line();
        std::string s = c.ident("a signal name");
        if (m && !m->signal(s)) fail(src_, l, "signal group " + g.name + ": signal '" + s + "' is not in " + m->name);
        g.signals.push_back(std::move(s));
        if (c.at_punct(',')) c.punct(',');
      }
      if (m) m->groups.push_back(std::move(g));
    } else if (kw == "BO_TX_BU_") {
      DbcMessage* m = message_ref(c);
      c.punct(':');
      std::vector<std::string> tx;
      while (!c.done()) {
        tx.push_back(c.ident("a node name"));
        if (c.at_punct(',')) c.punct(',');
      }
      if (m) m->transmitters = std::move(tx);
    }
    // Other statements (BA_REL_, EV_, ENVVAR_DATA_, SGTYPE_, SIG_TYPE_REF_, SG_MUL_VAL_,
    // CAT_DEF_, CAT_, FILTER, ...) carry nothing the rig decodes: read to ';' and skipped.
  }

  const std::string& src_;
  std::vector<Token> t_;
  Dbc db_;
  DbcMessage* cur_ = nullptr;
  DbcMessage pseudo_;
  std::set<uint32_t> pseudo_ids_;
  bool in_message_ = false;
};

Dbc Dbc::parse_file(const std::string& path) {
  // A FIFO, a terminal or a device named as the DBC would block the reader forever (found by
  // tests/fuzz/fuzz_hardware.cpp: dbc = "4" beside /proc/self/fd/N named a pipe).
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec) && std::filesystem::exists(path, ec))
    throw ConfigError(path + ": not a regular file (a DBC file is read whole)");
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open DBC file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path);
}

namespace {

// The bytes of a text that are not well-formed UTF-8 as Windows-1252, the code page Vector's
// CANdb++ writes DBC files in (cantools and canmatrix read them so): a unit "\xB5g" is "µg", a
// comment's "\xB0C" "°C". Bytes below 0x80 are the same in both, so names, numbers and line
// numbers do not move; the five bytes 1252 leaves undefined become the C1 controls of Latin-1,
// shown escaped. nullopt when every byte is UTF-8 already: the text is read as it is, uncopied.
std::optional<std::string> utf8_from_cp1252(const std::string& t) {
  static constexpr char16_t k80[32] = {0x20AC, 0x81,   0x201A, 0x0192, 0x201E, 0x2026, 0x2020, 0x2021,
                                       0x02C6, 0x2030, 0x0160, 0x2039, 0x0152, 0x8D,   0x017D, 0x8F,
                                       0x90,   0x2018, 0x2019, 0x201C, 0x201D, 0x2022, 0x2013, 0x2014,
                                       0x02DC, 0x2122, 0x0161, 0x203A, 0x0153, 0x9D,   0x017E, 0x0178};
  std::optional<std::string> out;
  for (std::size_t i = 0; i < t.size();) {
    const auto b = static_cast<unsigned char>(t[i]);
    // A well-formed UTF-8 sequence stays as it is: a CANdb++ file edited later in a UTF-8 editor
    // holds both (its "µg" in UTF-8 beside a 1252 "°"; a code review), and a byte-order mark is kept
    // for the tokenizer to skip.
    if (const std::size_t n = b < 0x80 ? 1 : utf8_sequence_at(t, i); n > 0) {
      if (out) out->append(t, i, n);
      i += n;
      continue;
    }
    if (!out) {  // the first byte that is not UTF-8: the text up to it, then as 1252
      out.emplace(t, 0, i);
      out->reserve(t.size() + t.size() / 8);
    }
    const char32_t u = b < 0xA0 ? k80[b - 0x80] : b;
    if (u < 0x800) {
      *out += static_cast<char>(0xC0 | (u >> 6));
      *out += static_cast<char>(0x80 | (u & 0x3F));
    } else {
      *out += static_cast<char>(0xE0 | (u >> 12));
      *out += static_cast<char>(0x80 | ((u >> 6) & 0x3F));
      *out += static_cast<char>(0x80 | (u & 0x3F));
    }
    ++i;
  }
  return out;
}

}  // namespace

Dbc Dbc::parse(const std::string& text, const std::string& src) {
  if (const std::optional<std::string> u = utf8_from_cp1252(text)) return DbcParser(*u, src).run();
  return DbcParser(text, src).run();
}

const DbcMessage* Dbc::find(uint32_t id, bool extended) const {
  for (const auto& m : messages_)
    if (m.id == id && m.extended == extended) return &m;
  return nullptr;
}

const DbcMessage* Dbc::find(uint32_t id) const {
  if (const DbcMessage* m = find(id, false)) return m;
  return find(id, true);
}

const DbcMessage* Dbc::find(const std::string& name) const {
  for (const auto& m : messages_)
    if (m.name == name) return &m;
  return nullptr;
}

std::optional<std::string> Dbc::attribute(const DbcAttributes& on, const std::string& name) const {
  if (auto it = on.find(name); it != on.end()) return it->second;
  if (auto d = attr_defs_.find(name); d != attr_defs_.end() && !d->second.default_value.empty())
    return d->second.default_value;
  return std::nullopt;
}

uint64_t dbc_extract_raw(std::span<const uint8_t> p, int start, int length, bool big_endian) {
  uint64_t v = 0;
  if (!big_endian && start % 8 == 0 && length % 8 == 0) {  // whole bytes: the common Intel case
    const int first = start / 8, n = length / 8;
    for (int k = n - 1; k >= 0; --k) {
      const auto idx = static_cast<std::size_t>(first + k);
      v = (v << 8) | (idx < p.size() ? p[idx] : 0);
    }
    return v;
  }
  for_each_bit(start, length, big_endian, [&](int k, int pos) {
    const auto idx = static_cast<std::size_t>(pos / 8);
    const uint64_t bit = idx < p.size() ? (p[idx] >> (pos % 8)) & 1u : 0u;
    if (big_endian)
      v = (v << 1) | bit;  // most significant bit first
    else
      v |= bit << k;
  });
  return v;
}

void dbc_insert_raw(std::span<uint8_t> p, int start, int length, bool big_endian, uint64_t raw) {
  for_each_bit(start, length, big_endian, [&](int k, int pos) {
    const auto idx = static_cast<std::size_t>(pos / 8);
    if (idx >= p.size()) return;
    const int bit_no = big_endian ? length - 1 - k : k;
    const auto bit = static_cast<uint8_t>(1u << (pos % 8));
    if ((raw >> bit_no) & 1u)
      p[idx] = static_cast<uint8_t>(p[idx] | bit);
    else
      p[idx] = static_cast<uint8_t>(p[idx] & ~bit);
  });
}

uint64_t dbc_extract_raw(const CanFrame& f, int start, int length) {
  return dbc_extract_raw(std::span<const uint8_t>(f.data.data(), f.data.size()), start, length, false);
}

namespace {
// raw as integer (signed or not) or IEEE float, then factor and offset.
double physical_of_raw(const DbcSignal& s, uint64_t raw) {
  double v;
  if (s.value_type == 1) {
    v = std::bit_cast<float>(static_cast<uint32_t>(raw));
  } else if (s.value_type == 2) {
    v = std::bit_cast<double>(raw);
  } else if (s.is_signed) {
    v = static_cast<double>(sign_extend(raw, s.length));
  } else {
    v = static_cast<double>(raw);
  }
  return v * s.factor + s.offset;
}
}  // namespace

double dbc_physical(const DbcSignal& s, std::span<const uint8_t> p) {
  return physical_of_raw(s, dbc_extract_raw(p, s.start, s.length, s.big_endian));
}

namespace {
__extension__ typedef __int128 Int128;  // GCC's and clang's; -Wpedantic asks for the marker
__extension__ typedef unsigned __int128 Uint128;
}  // namespace

std::string dbc_physical_exact(const DbcSignal& s, uint64_t raw) {
  // Below 2^53 a whole factor or offset is exactly what the DBC says; above it the double the
  // parser made may not be (9007199254740993 reads as ...992, a re-test), so no exact text.
  constexpr double k53 = 9007199254740992.0;
  const auto whole = [&](double v) { return v == std::trunc(v) && std::fabs(v) < k53; };
  if (s.value_type != 0 || !whole(s.factor) || !whole(s.offset)) return {};
  // |raw| < 2^64 and |factor|, |offset| < 2^53: the sum stays below 2^118.
  const Int128 r = s.is_signed ? static_cast<Int128>(sign_extend(raw, s.length)) : static_cast<Int128>(raw);
  const Int128 v = r * static_cast<int64_t>(s.factor) + static_cast<int64_t>(s.offset);
  Uint128 mag = static_cast<Uint128>(v < 0 ? -v : v);
  std::string digits;
  do {
    digits.insert(digits.begin(), static_cast<char>('0' + static_cast<int>(mag % 10)));
    mag /= 10;
  } while (mag != 0);
  return v < 0 ? "-" + digits : digits;
}

uint64_t dbc_raw_of(const DbcSignal& s, double physical) {
  if (s.value_type == 1) return std::bit_cast<uint32_t>(static_cast<float>((physical - s.offset) / s.factor));
  if (s.value_type == 2) return std::bit_cast<uint64_t>((physical - s.offset) / s.factor);
  const double r = std::nearbyint((physical - s.offset) / s.factor);
  const uint64_t mask = s.length >= 64 ? ~uint64_t{0} : (uint64_t{1} << s.length) - 1;
  const uint64_t bits = r < 0 ? static_cast<uint64_t>(static_cast<int64_t>(r)) : static_cast<uint64_t>(r);
  return bits & mask;
}

double dbc_physical(const DbcSignal& s, const CanFrame& f) {
  return dbc_physical(s, std::span<const uint8_t>(f.data.data(), f.data.size()));
}

namespace {

std::optional<std::vector<DecodedSignal>> decode_payload(const DbcMessage& m, std::span<const uint8_t> p,
                                                         std::string* error) {
  const int len = static_cast<int>(p.size());
  // A CAN FD frame is padded to the next valid length.
  if (len != m.dlc && !(m.dlc > 8 && len == canfd_round_up(m.dlc))) {
    if (error) *error = m.name + ": length " + std::to_string(len) + ", DBC says " + std::to_string(m.dlc);
    return std::nullopt;
  }
  std::optional<int64_t> mux;
  for (const auto& s : m.signals)
    if (s.multiplexor) mux = static_cast<int64_t>(dbc_extract_raw(p, s.start, s.length, s.big_endian));
  std::vector<DecodedSignal> out;
  for (const auto& s : m.signals) {
    if (s.mux_value && (!mux || *mux != *s.mux_value)) continue;
    const uint64_t raw = dbc_extract_raw(p, s.start, s.length, s.big_endian);
    DecodedSignal d{s.name, physical_of_raw(s, raw), s.unit, {}, raw};
    if (!s.value_names.empty() && s.value_type == 0) {
      const int64_t key = s.is_signed ? sign_extend(raw, s.length) : static_cast<int64_t>(raw);
      if (auto it = s.value_names.find(key); it != s.value_names.end()) d.value_name = it->second;
    }
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace

std::optional<std::vector<DecodedSignal>> Dbc::decode(const CanFrame& f, std::string* error) const {
  const DbcMessage* m = f.error ? nullptr : find(f.id, f.extended);
  if (!m) return std::nullopt;
  return decode_payload(*m, std::span<const uint8_t>(f.data.data(), std::min<std::size_t>(f.len, 8)), error);
}

std::optional<std::vector<DecodedSignal>> Dbc::decode(const CanFdFrame& f, std::string* error) const {
  const DbcMessage* m = f.error ? nullptr : find(f.id, f.extended);
  if (!m) return std::nullopt;
  return decode_payload(*m, std::span<const uint8_t>(f.data.data(), std::min<std::size_t>(f.len, 64)), error);
}

}  // namespace rig::link
