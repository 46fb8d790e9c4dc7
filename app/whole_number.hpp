// The one reader of a whole number typed on the command line (--taus m:LIST, --inject drop@SEQ:COUNT):
// the callers keep their own messages, this says only whether the text is one.
#pragma once
#include <charconv>
#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>
#include <system_error>

namespace rig::cli {

// The whole text as a decimal whole number in [least, most], or nothing. std::from_chars on an
// unsigned type takes digits only: no blank, no sign ('+' or '-'), no "0x"; a value past
// uint64 is out of range, not wrapped. No leading zero, as every whole number on the command
// line (README): "010" is a typo, and CLI11 reads it as octal 8 elsewhere.
inline std::optional<std::uint64_t> whole_number(std::string_view text, std::uint64_t least,
                                                 std::uint64_t most = std::numeric_limits<std::uint64_t>::max()) {
  if (text.empty() || (text.size() > 1 && text[0] == '0')) return std::nullopt;
  std::uint64_t v = 0;
  const char* const end = text.data() + text.size();
  const auto [stop, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc() || stop != end || v < least || v > most) return std::nullopt;
  return v;
}

// Whether `text` is a decimal whole number (digits, no leading zero) above `most`, uint64's
// range included: such a value is refused as too large, not as not being a number >= 1.
inline bool whole_number_above(std::string_view text, std::uint64_t most) {
  if (text.empty() || (text.size() > 1 && text[0] == '0')) return false;
  for (char c : text)
    if (c < '0' || c > '9') return false;
  std::uint64_t v = 0;
  const auto [stop, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  return ec == std::errc::result_out_of_range || v > most;
}

}  // namespace rig::cli
