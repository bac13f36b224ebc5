#pragma once
// Doubles as text, the same in every locale (std::to_chars never reads the locale). The one
// place the project turns a double into text outside JSON (whose dump() has its own rule:
// common/config_hash.hpp).
#include <charconv>
#include <cmath>
#include <string>

namespace dsb {

// as a message shows a value: the shortest text that reads back to the same double (0.1 -> "0.1",
// 1e-9 -> "1e-09", 3.0 -> "3"), and "nan", "inf", "-inf"
inline std::string number_text(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

// as a file stores a value for another program: 17 significant digits, printf's "%.17g" in the C
// locale (every double has its own text, and strtod or from_chars reads it back to the same bits)
inline std::string exact_number_text(double v) {
  char buf[40];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17).ptr);
}

}  // namespace dsb
