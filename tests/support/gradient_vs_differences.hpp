#pragma once
// Shared by the tests that hold an analytic gradient against central differences (the RL
// networks and losses, NLopt's gradient counts, PPO's end-to-end gradient): one central
// difference, and the two error measures of a whole gradient vector.
#include <algorithm>
#include <cmath>
#include <vector>

namespace dsb::testing {

// (f() with xi + h - f() with xi - h) / 2h, where f reads xi (a coordinate of the point it sees);
// xi is restored before returning
template <class F>
double central_difference(double& xi, double h, F&& f) {
  const double x0 = xi;
  xi = x0 + h;
  const double up = f();
  xi = x0 - h;
  const double down = f();
  xi = x0;
  return (up - down) / (2.0 * h);
}

// analytic gradient ga against differences gf (same length)
struct GradientError {
  double normwise;  // |ga - gf| / |gf|
  double max_rel;   // max_i |ga_i - gf_i| / max_i |gf_i|
};

inline GradientError gradient_error(const std::vector<double>& ga, const std::vector<double>& gf) {
  double num = 0, den = 0, maxd = 0, maxg = 0;
  for (std::size_t i = 0; i < ga.size(); ++i) {
    num += (ga[i] - gf[i]) * (ga[i] - gf[i]);
    den += gf[i] * gf[i];
    maxd = std::max(maxd, std::abs(ga[i] - gf[i]));
    maxg = std::max(maxg, std::abs(gf[i]));
  }
  return {std::sqrt(num / den), maxd / maxg};
}

}  // namespace dsb::testing
