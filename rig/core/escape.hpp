// One byte shown as text, "\xNN" (two upper-case hex digits): how every message, JUnit file
// and report shows a byte that must not reach a terminal or an XML reader as it is.
#pragma once
#include <string>
#include <string_view>

namespace rig {

inline void append_hex_escape(std::string& out, unsigned char c) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  out += "\\x";
  out += kHex[c >> 4];
  out += kHex[c & 0xF];
}

// A value as typed, for a message: printable ASCII as it is, every other byte as \xNN, so a
// control byte in a refused argument does not reach the terminal.
inline std::string shown_ascii(std::string_view v) {
  std::string shown;
  for (const char c : v) {
    if (c >= 0x20 && c <= 0x7E) {
      shown += c;
    } else {
      append_hex_escape(shown, static_cast<unsigned char>(c));
    }
  }
  return shown;
}

}  // namespace rig
