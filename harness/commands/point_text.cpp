#include "harness/commands/point_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "common/error.hpp"
#include "common/unit_box.hpp"

namespace dsb {

std::vector<double> parse_number_list(const std::string& option, const std::string& text) {
  std::vector<double> values;
  std::size_t pos = 0;
  while (true) {
    const std::size_t comma = text.find(',', pos);
    std::string token = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    // trim spaces
    const auto first = token.find_first_not_of(" \t");
    const auto last = token.find_last_not_of(" \t");
    token = first == std::string::npos ? "" : token.substr(first, last - first + 1);
    double v = 0.0;
    const char* begin = token.data();
    const char* end = token.data() + token.size();
    if (!token.empty() && *begin == '+') ++begin;
    const auto [ptr, ec] = std::from_chars(begin, end, v);
    if (!token.empty() && ec == std::errc::result_out_of_range && ptr == end) {
      // a number, but outside the normal doubles: a subnormal one is kept, else say which way it
      // falls out
      const double rounded = std::strtod(token.c_str(), nullptr);
      if (std::isfinite(rounded) && rounded != 0.0) {
        values.push_back(rounded);
        if (comma == std::string::npos) break;
        pos = comma + 1;
        continue;
      }
      throw UsageError(option + ": '" + token + "' " +
                       (std::isinf(rounded)
                            ? "overflows a double (its magnitude is above 1.8e308)"
                            : "underflows a double (its magnitude is below 4.9e-324); write 0 for zero"));
    }
    if (token.empty() || ec != std::errc() || ptr != end || !std::isfinite(v))
      throw UsageError(option + ": '" + token + "' is not a finite number");
    values.push_back(v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return values;
}

std::vector<double> checked_point(const Env& env, const std::string& x_text, const std::string& option) {
  const auto x = parse_number_list(option, x_text);
  if (static_cast<int>(x.size()) != env.dim())
    throw UsageError(fmt::format("{} has {} values, env '{}' needs {}", option, x.size(), env.name(), env.dim()));
  if (const auto i = first_outside_box(x); i >= 0)
    throw UsageError(fmt::format("{}: value {} at position {} is outside [-1, 1]", option, x[i], i));
  return x;
}

}  // namespace dsb
