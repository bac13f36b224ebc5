#pragma once
// Shared by the rigid env tests (bounce's plane, pinball's capsule): the penalty contact law's
// Jacobians df/dx and df/dv at one (p, v) against central differences of the force, and the
// gradient check options both envs' reverse passes are held to.
#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "envs/core/gradient_check.hpp"
#include "envs/rigid/contact.hpp"

namespace dsb::testing {

// every entry of df/dx and df/dv (D x D) within 1e-6 |central| + 1e-5 of the central difference
// with step h of force(p, v) (a ContactForce<D>); returns the largest |analytic - central| /
// (|central| + 1) over both; `point` names the point in failures
template <int D, class Force>
double expect_contact_jacobians_match(const Force& force, const Eigen::Matrix<double, D, 1>& p,
                                      const Eigen::Matrix<double, D, 1>& v, double h, int point) {
  using Vec = Eigen::Matrix<double, D, 1>;
  const ContactForce<D> c = force(p, v);
  double worst = 0.0;
  for (int j = 0; j < D; ++j) {
    const Vec e = Vec::Unit(j) * h;
    const Vec fdx = (force(p + e, v).f - force(p - e, v).f) / (2.0 * h);
    const Vec fdv = (force(p, v + e).f - force(p, v - e).f) / (2.0 * h);
    for (int i = 0; i < D; ++i) {
      EXPECT_NEAR(c.df_dx(i, j), fdx(i), 1e-6 * std::abs(fdx(i)) + 1e-5) << point << " " << i << j;
      EXPECT_NEAR(c.df_dv(i, j), fdv(i), 1e-6 * std::abs(fdv(i)) + 1e-5) << point << " " << i << j;
      worst = std::max(worst, std::abs(c.df_dx(i, j) - fdx(i)) / (std::abs(fdx(i)) + 1.0));
      worst = std::max(worst, std::abs(c.df_dv(i, j) - fdv(i)) / (std::abs(fdv(i)) + 1.0));
    }
  }
  return worst;
}

// |analytic - central| <= 1e-5 (|central| + 1) at step 1e-7: a relative tolerance with an
// absolute floor; loss() and loss_and_grad() bit-equal
inline GradientCheckOptions rigid_gradient_check_options() {
  GradientCheckOptions options;
  options.step = 1e-7;
  options.tolerance = 1e-5;
  options.relative_floor = 0.0;
  options.absolute_floor = 1.0;
  return options;
}

}  // namespace dsb::testing
