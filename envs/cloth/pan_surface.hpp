#pragma once
// A round frying pan as a moving contact surface of the cloth engine (cloth_model.hpp), for the
// `flip` task: a flat disc of radius flat_radius blended into a rim that rises to rim_height at the
// outer radius, as a surface of revolution y_local = h(r) about the pan's local y axis:
//   h(r) = 0                                                         r <= flat_radius
//   h(r) = rim_height u^3, u = (r - flat_radius) / (radius - flat_radius)   flat_radius < r <= radius
// The cubic is the lowest power whose join with the disc is C2 (h = h' = h'' = 0 at u = 0): the
// normal and its Jacobian dnormal/dx, which the reverse pass uses, are continuous everywhere on the
// pan, so a gradient window straddling the join sees no jump of either; the rim is steepest at its
// top edge (slope 3 rim_height / (radius - flat_radius)), a pan's wall, not a bowl's lip.
//
// Pose: the pan is moved in the vertical x-y plane and tilted about the z axis through its centre
// (the seed's 3 DOF: x, y, tilt). Pose P = (cx, cy, theta): local coordinates of a world point x
// are l = R(theta)^T (x - c), c = (cx, cy, 0), R the rotation by theta about +z. The pose of the
// pan at time t dt is row t of a path table (steps + 1 rows) the episode sets (set_path); during
// step t the pan moves with the constant velocity of the path's chord: centre velocity (c(t+1) -
// c(t)) / dt and angular velocity omega = (theta(t+1) - theta(t)) / dt about +z, so the surface
// velocity at x is u(x) = vc + omega z x (x - c(t)) (a rigid motion; du/dx = omega [z]_x).
//
// Sample at x, step t (pose row t): with l and r = |(l_x, l_z)|, the local normal of the graph is N
// = (-g l_x, 1, -g l_z) with g = h'(r) / r, the signed distance is the first-order distance to the
// graph (l_y - h(r)) / |N| (exact on the flat disc), the normal n = R N / |N|. Contact region: r <=
// radius and distance > -thickness: the pan is a shell of that thickness; below it (under the pan)
// and beyond the outer radius there is no pan (distance reported as +1 m).
//
// Parameters (param_count = 3 (steps + 1)): the path table, row-major (cx, cy, theta) per time.
// sample_adjoint adds dLoss/d(rows t and t + 1) for the normal's and velocity's dependence on the
// pose (the normal through c(t), theta(t); the velocity through both rows).
#include <span>
#include <vector>

#include "envs/cloth/cloth_model.hpp"

namespace dsb::cloth {

struct PanShape {
  double radius = 0.2;        // m, outer radius (the seed's 20 cm)
  double flat_radius = 0.14;  // m, radius of the flat bottom
  double rim_height = 0.03;   // m, height of the rim's top edge above the bottom
  double thickness = 0.02;    // m, depth of the contact shell below the surface
  // throws ConfigError("pan", field, why)
  void validate() const;
  // h(r), h'(r), h''(r)
  void profile(double r, double& h, double& dh, double& d2h) const;
};

struct PanPose {
  double x = 0.0, y = 0.0, tilt = 0.0;  // m, m, rad
};

class PanSurface final : public ContactSurface {
 public:
  explicit PanSurface(PanShape shape);
  const PanShape& shape() const { return shape_; }
  // the pose path for the next episode: (steps + 1) rows, times 0 .. steps; dt the step
  void set_path(std::span<const PanPose> path, double dt);
  // replace row t of the path (the RL view sets the path interval by interval)
  void set_pose(int t, const PanPose& pose);
  int steps() const { return static_cast<int>(path_.size()) - 1; }
  const PanPose& pose(int t) const { return path_[t]; }

  SurfaceSample sample(int step, const Vec3& x) const override;
  int param_count() const override { return 3 * static_cast<int>(path_.size()); }
  void sample_adjoint(int step, const Vec3& x, const Vec3& normal_bar, const Vec3& velocity_bar,
                      std::span<double> param_bar) const override;

  // world point of a local point l at pose p: c + R(tilt) l
  static Vec3 to_world(const PanPose& p, const Vec3& local);

 private:
  struct Row {
    double c = 1.0, s = 0.0;  // cos, sin of the tilt (det_math)
  };
  // local normal pieces at local point l: N / |N| and d(N/|N|)/dl; false outside the contact region
  bool local_normal(const Vec3& l, double& distance, Vec3& n, Mat3& dn_dl) const;

  PanShape shape_;
  double dt_ = 1e-3;
  std::vector<PanPose> path_;  // (steps + 1)
  std::vector<Row> trig_;      // (steps + 1)
};

}  // namespace dsb::cloth
