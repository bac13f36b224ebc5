#include "harness/core/shell_word.hpp"

#include <regex>

namespace dsb {

std::string shell_word(const std::string& s) {
  static const std::regex safe("[A-Za-z0-9_@%+=:,./-]+");
  if (std::regex_match(s, safe)) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace dsb
