// One byte shown as text, "\xNN" (two upper-case hex digits): how every message, JUnit file
// and report shows a byte that must not reach a terminal or an XML reader as it is.
#pragma once
#include <string>

namespace rig {

inline void append_hex_escape(std::string& out, unsigned char c) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  out += "\\x";
  out += kHex[c >> 4];
  out += kHex[c & 0xF];
}

}  // namespace rig
