#pragma once
// Small test functions with gradients shared by the optimizer tests.
#include <span>

#include "tests/support/function_objective.hpp"

namespace dsb::testing {

// f(x) = sum (x_i - c_i)^2 with c_i = c0 - dc i (minimum 0 inside the box), gradient into g when
// g is non-empty
inline double shifted_sphere(std::span<const double> x, std::span<double> g, double c0, double dc) {
  double f = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double d = x[i] - (c0 - dc * static_cast<double>(i));
    f += d * d;
    if (!g.empty()) g[i] = 2.0 * d;
  }
  return f;
}

// a budgeted objective over shifted_sphere, with its gradient
inline FunctionObjective shifted_sphere_objective(int dim, std::int64_t budget, double c0, double dc) {
  return FunctionObjective(
      dim, budget, [=](std::span<const double> x) { return shifted_sphere(x, {}, c0, dc); },
      [=](std::span<const double> x, std::span<double> g) { return shifted_sphere(x, g, c0, dc); });
}

}  // namespace dsb::testing
