// Escaping text for XML and HTML (JUnit files, report.html, SVG): the five characters
// that are markup in either. &#39; rather than &apos; so the same text is valid HTML 4 too.
#pragma once
#include <string>
#include <string_view>

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
      default: out += c;
    }
  }
  return out;
}

}  // namespace rig
