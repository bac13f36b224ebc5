#pragma once
// Rigid primitives of the MPM engine: an analytic SDF shape (sdf.hpp), a pose that moves with
// the actions, and PlasticineLab's grid contact (its primitives' SDF collision), each with
// its adjoint.
//
// Kinematics per substep (PlasticineLab: an env step's action, scaled and divided by the
// substeps, is a displacement held for each of its substeps):
//  - `fixed`: never moves (e.g. Rope's pillar).
//  - `translate`: displacement d = sum_k a_k scale_k e_{axis_k} / substeps; p' = clamp(p + d,
//    lower, upper); rotation constant.
//  - `rolling_pin` (a = roll dw, yaw dth, vertical dy, each x scale / substeps):
//    R' = Ry(-dth) R Ry_body(dw), p' = clamp(p + t) with t = (e_y x u) dw roll_radius, u = R (0,-1,0),
//    and t_y replaced by dy (PlasticineLab's "rolling without slip", roll_radius 0.03).
// Contact with a grid node x of velocity v (before the floor and walls): with the pose of
// substep f, d = sdf(R_f^T (x - p_f)), n = R_f grad sdf, influence = min(exp(-d softness), 1);
// active when d <= 0 or (softness > 0 and influence > 0.1); the collider's velocity at x is
// v_c = (R_{f+1} R_f^T (x - p_f) + p_{f+1} - x) / dt; u = v - v_c, u_n = u.n; when u_n < 0 the
// normal part is removed and Coulomb friction shortens the tangential part,
// u_t = (u - u_n n) max(0, |u - u_n n| + friction u_n) / |u - u_n n|; otherwise u_t = u;
// v' = v_c + (1 - influence) u + influence u_t.
// Pose adjoints are kept as (dL/dp, dL/dtheta) with theta the world-frame rotation tangent
// (R -> Exp(theta) R).
#include <array>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "envs/mpm/mpm_types.hpp"
#include "envs/mpm/sdf.hpp"

namespace dsb::mpm {

enum class PrimitiveMotion { fixed, translate, rolling_pin };

struct PrimitiveSpec {
  std::string name;
  Shape shape;
  Vec3 position = Vec3(0.5, 0.5, 0.5);
  std::array<double, 4> rotation = {1.0, 0.0, 0.0, 0.0};  // quaternion (w, x, y, z), PlasticineLab order
  double friction = 0.9;                                  // PlasticineLab's primitive default
  double softness = 0.0;  // 0: hard contact (d <= 0 only); PlasticineLab's gradient solver: 666
  PrimitiveMotion motion = PrimitiveMotion::fixed;
  std::vector<int> action_axes;      // translate: world axis of each action component
  std::vector<double> action_scale;  // displacement (or angle) per env step at action 1, per component
  double roll_radius = 0.03;         // rolling_pin: translation per radian of roll
  Vec3 lower_bound = Vec3::Zero();   // position clamp
  Vec3 upper_bound = Vec3::Ones();

  int action_dim() const;
  void validate(const std::string& owner, const std::string& field) const;
  nlohmann::json to_json() const;
};

struct Pose {
  Vec3 p = Vec3::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

struct PoseAdjoint {
  Vec3 p = Vec3::Zero();
  Vec3 theta = Vec3::Zero();
  PoseAdjoint& operator+=(const PoseAdjoint& o) {
    p += o.p;
    theta += o.theta;
    return *this;
  }
};

Pose initial_pose(const PrimitiveSpec& spec);

// Kinematics of one substep. `action` has spec.action_dim() entries in [-1, 1].
Pose advance_pose(const PrimitiveSpec& spec, const Pose& pose, const double* action, int substeps);

// Adjoint of advance_pose: `bar` holds dL/d(pose after) on entry and dL/d(pose before) on exit;
// dL/daction is added to action_bar.
void advance_pose_adjoint(const PrimitiveSpec& spec, const Pose& pose, const double* action, int substeps,
                          PoseAdjoint& bar, double* action_bar);

// The contact geometry of one primitive over one substep (poses f and f + 1).
struct ContactFrame {
  Mat3 R0;      // rotation at f
  Vec3 p0, p1;  // positions at f and f + 1
  Mat3 M;       // R_{f+1} R_f^T
  double inv_dt = 0.0;
  double reach = 0.0;  // nodes farther than this from p0 cannot be in contact (bounding radius + band)
};
ContactFrame contact_frame(const PrimitiveSpec& spec, const Pose& at_f, const Pose& at_f1, double dt);

// Contact at a grid node; returns the node's new velocity.
Vec3 collide(const PrimitiveSpec& spec, const ContactFrame& frame, const Vec3& x, const Vec3& v);

// Adjoint of collide: returns dL/dv given dL/dv'; adds to the pose adjoints of f and f + 1.
Vec3 collide_adjoint(const PrimitiveSpec& spec, const ContactFrame& frame, const Vec3& x, const Vec3& v,
                     const Vec3& v_out_bar, PoseAdjoint& at_f, PoseAdjoint& at_f1);

// Signed distance of a world point to the primitive at a pose (losses, tests).
double primitive_distance(const PrimitiveSpec& spec, const Pose& pose, const Vec3& x);
// ... and its gradients: dL/dx and the pose adjoint, for dL/d(distance) = d_bar.
void primitive_distance_adjoint(const PrimitiveSpec& spec, const Pose& pose, const Vec3& x, double d_bar, Vec3& x_bar,
                                PoseAdjoint& pose_bar);

// Radius of a sphere around the local origin that contains the shape.
double bounding_radius(const Shape& shape);

}  // namespace dsb::mpm
