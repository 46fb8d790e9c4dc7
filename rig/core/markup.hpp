// Escaping text for XML and HTML (JUnit files, report.html, SVG): the five characters
// that are markup in either. &#39; rather than &apos; so the same text is valid HTML 4 too.
#pragma once
#include <string>
#include <string_view>

#include "rig/core/escape.hpp"

namespace rig {

inline std::string markup_escape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      case '\t': case '\n': case '\r': out += c; break;
      default:
        // XML 1.0 has no way to carry the other C0 controls (not even as &#1;): a reader stops at
        // them as "not well-formed" (a serial with 0x01 broke junit.xml, a review). Shown as text.
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) {
          append_hex_escape(out, static_cast<unsigned char>(c));
        } else {
          out += c;
        }
    }
  }
  return out;
}

}  // namespace rig
