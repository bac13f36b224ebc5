#pragma once
// The short-horizon variants of the particle envs, BASE-hN: the first N env steps of BASE's
// episode. One env has one name, and so one run key: N is written without leading zeros and is a
// multiple of `multiple` from `multiple` to full_steps - multiple; the full horizon is BASE itself.
// (fluid-h05 and fluid-h50 would otherwise repeat fluid-h5's and fluid's numbers under new keys.)
#include <optional>
#include <string>

namespace dsb {

// N for requested = BASE-hN; nullopt when requested does not start with "BASE-h". UsageError
// naming the canonical name (leading zeros, N = full_steps) or the allowed range otherwise.
std::optional<int> parse_horizon_name(const std::string& requested, const std::string& base, int full_steps,
                                      int multiple);

}  // namespace dsb
