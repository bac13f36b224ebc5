#pragma once
// A value from the user (a name, a path, a number's text) as an error message echoes it: control
// characters (C0, DEL) written as escapes (\n, \t, \x1b, ...), so that a message stays one line and
// a value cannot move the cursor, clear the screen or forge a second line on the user's terminal.
// Printable bytes, UTF-8 included, are kept as they are.
#include <cstdio>
#include <string>
#include <string_view>

namespace dsb {

inline std::string shown_value(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
      continue;
    }
    switch (c) {
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default: {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\x%02x", u);
        out += buf;
      }
    }
  }
  return out;
}

}  // namespace dsb
