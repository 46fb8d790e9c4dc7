// A double in a message as its shortest text that reads back to the same double (C++17
// std::to_chars): the digits a user typed, not toml++'s 17 nor a stream's 6.
#pragma once
#include <charconv>
#include <string>

namespace rig {

inline std::string shortest_text(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

}  // namespace rig
