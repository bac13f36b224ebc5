#pragma once
// Finite differences of an env's loss, the oracle every gradient test compares against.
#include <span>
#include <vector>

#include "envs/core/env.hpp"

namespace dsb::testing {

struct Differences {
  double central, right, left;  // (f(x+h) - f(x-h)) / 2h, (f(x+h) - f(x)) / h, (f(x) - f(x-h)) / h
};

// central and one-sided differences of the loss along coordinate i
inline Differences differences(const Env& env, std::vector<double> x, int i, double h) {
  const double f0 = env.loss(x);
  const double xi = x[i];
  x[i] = xi + h;
  const double fp = env.loss(x);
  x[i] = xi - h;
  const double fm = env.loss(x);
  return {(fp - fm) / (2.0 * h), (fp - f0) / h, (f0 - fm) / h};
}

// central differences along every coordinate
inline std::vector<double> central_differences(const Env& env, const std::vector<double>& x, double h) {
  std::vector<double> g(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) g[i] = differences(env, x, static_cast<int>(i), h).central;
  return g;
}

}  // namespace dsb::testing
