// One byte shown as text, "\xNN" (two upper-case hex digits): how every message, JUnit file
// and report shows a byte that must not reach a terminal or an XML reader as it is.
#pragma once
#include <cctype>
#include <cstddef>
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

// The length of the well-formed UTF-8 sequence at s[i] (RFC 3629: no overlong form, no
// surrogate, nothing past U+10FFFF), or 0 when the byte there starts none.
inline std::size_t utf8_sequence_at(std::string_view s, std::size_t i) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const auto cont = [&](std::size_t k) { return k < s.size() && (b(k) & 0xC0) == 0x80; };
  const unsigned char c = b(i);
  if (c >= 0xC2 && c <= 0xDF) return cont(i + 1) ? 2 : 0;
  if (c >= 0xE0 && c <= 0xEF) {
    if (!cont(i + 1) || !cont(i + 2)) return 0;
    if ((c == 0xE0 && b(i + 1) < 0xA0) || (c == 0xED && b(i + 1) > 0x9F)) return 0;
    return 3;
  }
  if (c >= 0xF0 && c <= 0xF4) {
    if (!cont(i + 1) || !cont(i + 2) || !cont(i + 3)) return 0;
    if ((c == 0xF0 && b(i + 1) < 0x90) || (c == 0xF4 && b(i + 1) > 0x8F)) return 0;
    return 4;
  }
  return 0;
}

// Where to cut `s` at or before `n` (n < s.size()) so that no UTF-8 character is split: back
// from n past continuation bytes, no further than `floor`. For quoting the start of a long value.
inline std::size_t utf8_cut(std::string_view s, std::size_t n, std::size_t floor = 0) {
  while (n > floor && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
  return n;
}

// Characters a terminal acts on rather than shows, though well-formed: the C1 controls
// (U+0080..U+009F: U+009B is CSI), the line and paragraph separators, and the bidirectional
// embeddings, overrides and isolates (U+202A..U+202E, U+2066..U+2069); and those it shows as
// nothing, which hide in a quoted value (a byte-order mark inside a file made "not a decimal
// number: '4'", a review): the soft hyphen U+00AD, the zero-width space, joiners and marks
// U+200B..U+200F, the word joiner and invisible operators U+2060..U+2064, and U+FEFF.
inline bool terminal_acts_on(std::string_view seq) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(seq[k]); };
  if (seq.size() == 2) return b(0) == 0xC2 && (b(1) <= 0x9F || b(1) == 0xAD);
  if (seq.size() == 3 && b(0) == 0xE2 && b(1) == 0x80)
    return (b(2) >= 0x8B && b(2) <= 0x8F) || b(2) == 0xA8 || b(2) == 0xA9 || (b(2) >= 0xAA && b(2) <= 0xAE);
  if (seq.size() == 3 && b(0) == 0xE2 && b(1) == 0x81) return (b(2) >= 0xA0 && b(2) <= 0xA4) || (b(2) >= 0xA6 && b(2) <= 0xA9);
  if (seq.size() == 3) return b(0) == 0xEF && b(1) == 0xBB && b(2) == 0xBF;
  return false;
}

// Text as rig analyze shows a bad line (its quoted_bytes): printable ASCII and whole UTF-8
// characters (a Cyrillic name) as they are; control bytes, bytes that are not well-formed UTF-8
// and characters a terminal acts on as \xNN, byte by byte. For a name or a path in a message.
inline std::string shown_text(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t len = c >= 0x20 && c < 0x7F ? 1 : c >= 0x80 ? utf8_sequence_at(s, i) : 0;
    const bool shown_as_is = len == 1 || (len > 1 && !terminal_acts_on(s.substr(i, len)));
    if (len == 0) len = 1;
    for (std::size_t k = i; k < i + len; ++k)
      if (shown_as_is) out += s[k];
      else append_hex_escape(out, static_cast<unsigned char>(s[k]));
    i += len;
  }
  return out;
}

// `s` as one word a POSIX shell reads back to it, for a command a message offers to paste: as it
// is where it holds only characters no shell treats specially; else in single quotes; else, where
// shown_text would escape a byte (a newline in a folder name), in bash's $'...' with \xNN (the
// hint said `--resume /tmp/we ird\x0Aname`, which no shell reads as that folder: a review).
inline std::string shell_word(std::string_view s) {
  constexpr std::string_view plain = "_./:@%+=,-";
  bool bare = !s.empty(), hex = false;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t len = c >= 0x20 && c < 0x7F ? 1 : c >= 0x80 ? utf8_sequence_at(s, i) : 0;
    const bool as_is = len == 1 || (len > 1 && !terminal_acts_on(s.substr(i, len)));
    hex = hex || !as_is;
    bare = bare && as_is && (len > 1 || std::isalnum(c) || plain.find(static_cast<char>(c)) != std::string_view::npos);
    i += len == 0 ? 1 : len;
  }
  if (bare) return std::string(s);
  std::string out = hex ? "$'" : "'";
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t len = c >= 0x20 && c < 0x7F ? 1 : c >= 0x80 ? utf8_sequence_at(s, i) : 0;
    const bool as_is = len == 1 || (len > 1 && !terminal_acts_on(s.substr(i, len)));
    if (len == 0) len = 1;
    for (std::size_t k = i; k < i + len; ++k) {
      const char b = s[k];
      if (!as_is) append_hex_escape(out, static_cast<unsigned char>(b));
      else if (b == '\'') out += hex ? "\\'" : "'\\''";
      else if (b == '\\' && hex) out += "\\\\";
      else out += b;
    }
    i += len;
  }
  return out + "'";
}

// The offset of the first byte of `s` that is not in well-formed UTF-8 (a Latin-1 file name),
// or npos when `s` is UTF-8 throughout: JSON holds only UTF-8 text.
inline std::size_t first_non_utf8(std::string_view s) {
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t len = static_cast<unsigned char>(s[i]) < 0x80 ? 1 : utf8_sequence_at(s, i);
    if (len == 0) return i;
    i += len;
  }
  return std::string_view::npos;
}

// Whether shown_text would escape anything: `s` holds a control byte, a byte that is not
// well-formed UTF-8 or a character a terminal acts on.
inline bool has_unshowable(std::string_view s) { return shown_text(s) != s; }

}  // namespace rig
