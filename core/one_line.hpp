// A message as one line: control characters (a newline in a file or key name, say) written as
// escapes, so that an error stays the one line the commands promise.
#pragma once
#include <cstdio>
#include <string>

namespace deformlab {

inline std::string one_line(const std::string& s) {
  std::string out;
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c != 0x7f) {
      out += ch;
    } else if (ch == '\n') {
      out += "\\n";
    } else {
      char esc[5];
      std::snprintf(esc, sizeof esc, "\\x%02x", c);
      out += esc;
    }
  }
  return out;
}

}  // namespace deformlab
