#include "envs/core/horizon_name.hpp"

#include <algorithm>

#include "common/error.hpp"

namespace dsb {

std::optional<int> parse_horizon_name(const std::string& requested, const std::string& base, int full_steps,
                                      int multiple) {
  const std::string prefix = base + "-h";
  if (requested.rfind(prefix, 0) != 0) return std::nullopt;
  const std::string digits = requested.substr(prefix.size());
  const std::string rule = base + "-hN: N env steps, a multiple of " + std::to_string(multiple) + " from " +
      std::to_string(multiple) + " to " + std::to_string(full_steps - multiple) + "; all " +
      std::to_string(full_steps) + " is '" + base + "'";
  const bool numeric = !digits.empty() && digits.size() <= 6 &&
      std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!numeric) throw UsageError("unknown env '" + requested + "' (" + rule + ")");
  const int steps = std::stoi(digits);
  const bool in_range = steps >= multiple && steps <= full_steps && steps % multiple == 0;
  if (!in_range) throw UsageError("unknown env '" + requested + "' (" + rule + ")");
  if (steps == full_steps)
    throw UsageError("env '" + requested + "' is the full horizon: name it '" + base + "' (" + rule + ")");
  const std::string canonical = prefix + std::to_string(steps);
  if (requested != canonical) throw UsageError("env '" + requested + "' is written '" + canonical + "' (" + rule + ")");
  return steps;
}

}  // namespace dsb
