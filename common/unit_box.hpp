#pragma once
// The normalized box [-1, 1]^d: every env maps it to its physical parameters, and every optimizer
// searches it. The one test of whether a point lies in it.
#include <cstddef>
#include <span>

namespace dsb {

// the index of the first coordinate outside [-1, 1] (NaN is outside), or -1 when x is inside
inline std::ptrdiff_t first_outside_box(std::span<const double> x) {
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!(x[i] >= -1.0 && x[i] <= 1.0)) return static_cast<std::ptrdiff_t>(i);
  return -1;
}

inline bool inside_box(std::span<const double> x) { return first_outside_box(x) < 0; }

}  // namespace dsb
