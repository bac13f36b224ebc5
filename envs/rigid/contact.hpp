#pragma once
// The penalty contact law shared by `bounce` (3-D) and the pinballs (2-D), and its derivative.
//
// A ball is a point mass with a contact radius r. Against a surface with signed distance d of the
// ball centre p and unit outward normal n at the closest point, the law (ContactConfig) is
//   penetration  c   = max(0, r - d)
//   normal force f_n = max(0, ke c - kd min(v_n, 0)),   v_n = v . n          (never pulling)
//   friction     f_t = -mu f_n v_t / sqrt(|v_t|^2 + eps^2),  v_t = v - v_n n  (smooth Coulomb)
//   force        f   = f_n n + f_t
// The surfaces are static, so v is also the relative velocity. With c > 0 both normal terms are
// >= 0, so the clamp of f_n never bites in practice; it is kept so that the law never pulls.
//
// Derivatives: contact_force returns f and its Jacobians with respect to the centre p and the
// velocity v. At the switches of max/min (c = 0, v_n = 0, f_n = 0) the derivative is the one-sided
// derivative of the branch the code takes (contact only when c > 0, damping only when v_n < 0):
// the exact derivative of our discrete simulation almost everywhere. A distance function has
// gradient n (dd/dp = n^T), so the geometry only supplies d, n and dn/dp.
#include <Eigen/Dense>

#include "envs/rigid/contact_config.hpp"

namespace dsb {

// closest-point geometry of a ball centre against one surface
template <int D>
struct ContactGeometry {
  double distance = 0.0;                                                         // signed distance of the centre (m)
  Eigen::Matrix<double, D, 1> normal = Eigen::Matrix<double, D, 1>::Zero();      // unit outward normal (D)
  Eigen::Matrix<double, D, D> dnormal_dx = Eigen::Matrix<double, D, D>::Zero();  // dn/dp (D x D)
};

// the force of one contact on the ball and its Jacobians
template <int D>
struct ContactForce {
  bool active = false;        // c > 0 and f_n > 0; when false every other member is zero
  double penetration = 0.0;   // c (m)
  double normal_force = 0.0;  // f_n (N)
  Eigen::Matrix<double, D, 1> f = Eigen::Matrix<double, D, 1>::Zero();      // force (N) (D)
  Eigen::Matrix<double, D, D> df_dx = Eigen::Matrix<double, D, D>::Zero();  // df/dp (D x D)
  Eigen::Matrix<double, D, D> df_dv = Eigen::Matrix<double, D, D>::Zero();  // df/dv (D x D)
};

// plane {y : normal . y = offset} with unit `normal` pointing into the free side
template <int D>
ContactGeometry<D> plane_geometry(const Eigen::Matrix<double, D, 1>& p, const Eigen::Matrix<double, D, 1>& normal,
                                  double offset);

// 2-D capsule: the segment centre + s axis, |s| <= half_length (unit `axis`), inflated by
// `radius`. Distance = |p - closest point on the segment| - radius. Undefined (normal zero, the
// force inactive) only when p lies exactly on the segment, deep inside the paddle.
ContactGeometry<2> capsule_geometry(const Eigen::Vector2d& p, const Eigen::Vector2d& centre,
                                    const Eigen::Vector2d& axis, double half_length, double radius);

// the penalty force of one contact on a ball of contact radius `ball_radius` moving at v
template <int D>
ContactForce<D> contact_force(const ContactConfig& cfg, double ball_radius, const ContactGeometry<D>& g,
                              const Eigen::Matrix<double, D, 1>& v);

}  // namespace dsb
