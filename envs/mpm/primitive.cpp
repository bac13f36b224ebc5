#include "envs/mpm/primitive.hpp"

#include <algorithm>
#include <cmath>

#include "common/det_math.hpp"
#include "common/error.hpp"

namespace dsb::mpm {

namespace {

constexpr double kLn10 = 2.302585092994045684;  // influence > 0.1  <=>  d softness < ln 10

Eigen::Quaterniond about_y(double angle) {
  double s, c;
  dm::sincos(0.5 * angle, &s, &c);
  return Eigen::Quaterniond(c, 0.0, s, 0.0);
}

Mat3 rotation_y(double angle) {
  double s, c;
  dm::sincos(angle, &s, &c);
  Mat3 R;
  R << c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c;
  return R;
}

Vec3 clamp3(const Vec3& v, const Vec3& lo, const Vec3& hi, Vec3* mask) {
  Vec3 out;
  for (int a = 0; a < 3; ++a) {
    out[a] = std::min(std::max(v[a], lo[a]), hi[a]);
    if (mask) (*mask)[a] = (v[a] >= lo[a] && v[a] <= hi[a]) ? 1.0 : 0.0;
  }
  return out;
}

nlohmann::json shape_json(const Shape& s) {
  nlohmann::json j = {{"kind", shape_kind_name(s.kind)}};
  switch (s.kind) {
    case ShapeKind::sphere: j["radius"] = s.radius; break;
    case ShapeKind::capsule:
    case ShapeKind::cylinder:
      j["radius"] = s.radius;
      j["half_height"] = s.half_height;
      break;
    case ShapeKind::torus:
      j["major_radius"] = s.major_radius;
      j["radius"] = s.radius;
      break;
    case ShapeKind::box: j["half_extents"] = {s.half_extents.x(), s.half_extents.y(), s.half_extents.z()}; break;
    case ShapeKind::bowl:
      j["radius"] = s.radius;
      j["thickness"] = s.thickness;
      j["rim_height"] = s.rim_height;
      break;
  }
  return j;
}

const char* motion_name(PrimitiveMotion m) {
  switch (m) {
    case PrimitiveMotion::fixed: return "fixed";
    case PrimitiveMotion::translate: return "translate";
    case PrimitiveMotion::rolling_pin: return "rolling_pin";
  }
  return "?";
}

// translate: d = sum_k a_k scale_k e_axis_k / substeps
Vec3 translation(const PrimitiveSpec& spec, const double* action, double inv_n) {
  Vec3 d = Vec3::Zero();
  for (std::size_t k = 0; k < spec.action_axes.size(); ++k)
    d[spec.action_axes[k]] += action[k] * spec.action_scale[k] * inv_n;
  return d;
}

// rolling_pin: one substep's roll, yaw and vertical move, the pin's axis direction u = R (0,-1,0)
// and the translation t = (e_y x u) dw roll_radius with t_y = dy
struct RollStep {
  double dw, dth, dy;
  Vec3 u, t;
};
RollStep roll_step(const PrimitiveSpec& spec, const Pose& pose, const double* action, double inv_n) {
  RollStep r;
  r.dw = action[0] * spec.action_scale[0] * inv_n;
  r.dth = action[1] * spec.action_scale[1] * inv_n;
  r.dy = action[2] * spec.action_scale[2] * inv_n;
  r.u = -(pose.q.toRotationMatrix().col(1));
  r.t = Vec3(spec.roll_radius * r.dw * r.u.z(), r.dy, -spec.roll_radius * r.dw * r.u.x());
  return r;
}

}  // namespace

int PrimitiveSpec::action_dim() const {
  switch (motion) {
    case PrimitiveMotion::fixed: return 0;
    case PrimitiveMotion::translate: return static_cast<int>(action_axes.size());
    case PrimitiveMotion::rolling_pin: return 3;
  }
  return 0;
}

void PrimitiveSpec::validate(const std::string& owner, const std::string& field) const {
  auto fail = [&](const std::string& f, const std::string& why) { throw ConfigError(owner, field + "." + f, why); };
  try {
    shape.validate();
  } catch (const UsageError& e) {
    throw ConfigError(owner, field + ".shape", e.what());
  }
  if (!position.allFinite()) fail("position", "must be finite");
  const double qn = std::sqrt(rotation[0] * rotation[0] + rotation[1] * rotation[1] + rotation[2] * rotation[2] +
                              rotation[3] * rotation[3]);
  if (!(std::abs(qn - 1.0) < 1e-6)) fail("rotation", "must be a unit quaternion, norm " + std::to_string(qn));
  if (!(std::isfinite(friction) && friction >= 0.0)) fail("friction", "must be finite and >= 0");
  if (!(std::isfinite(softness) && softness >= 0.0)) fail("softness", "must be finite and >= 0");
  if (!(std::isfinite(roll_radius) && roll_radius >= 0.0)) fail("roll_radius", "must be finite and >= 0");
  for (int a = 0; a < 3; ++a)
    if (!(lower_bound[a] <= upper_bound[a])) fail("upper_bound", "must be >= lower_bound in every component");
  if (motion == PrimitiveMotion::translate) {
    if (action_axes.empty() || action_axes.size() > 3) fail("action_axes", "must have 1..3 axes");
    for (int a : action_axes)
      if (a < 0 || a > 2) fail("action_axes", "must be 0, 1 or 2, got " + std::to_string(a));
  }
  if (static_cast<int>(action_scale.size()) != action_dim())
    fail("action_scale",
         "must have " + std::to_string(action_dim()) + " entries, got " + std::to_string(action_scale.size()));
  for (double s : action_scale)
    if (!std::isfinite(s)) fail("action_scale", "must be finite");
  if (!(position.array() >= lower_bound.array()).all() || !(position.array() <= upper_bound.array()).all())
    fail("position", "must lie inside [lower_bound, upper_bound]");
}

nlohmann::json PrimitiveSpec::to_json() const {
  nlohmann::json j = {{"name", name},
                      {"shape", shape_json(shape)},
                      {"position", {position.x(), position.y(), position.z()}},
                      {"rotation_wxyz", rotation},
                      {"friction", friction},
                      {"softness", softness},
                      {"motion", motion_name(motion)},
                      {"action_scale", action_scale},
                      {"lower_bound", {lower_bound.x(), lower_bound.y(), lower_bound.z()}},
                      {"upper_bound", {upper_bound.x(), upper_bound.y(), upper_bound.z()}}};
  if (motion == PrimitiveMotion::translate) j["action_axes"] = action_axes;
  if (motion == PrimitiveMotion::rolling_pin) j["roll_radius"] = roll_radius;
  return j;
}

Pose initial_pose(const PrimitiveSpec& spec) {
  Pose pose;
  pose.p = spec.position;
  pose.q = Eigen::Quaterniond(spec.rotation[0], spec.rotation[1], spec.rotation[2], spec.rotation[3]).normalized();
  return pose;
}

Pose advance_pose(const PrimitiveSpec& spec, const Pose& pose, const double* action, int substeps) {
  const double inv_n = 1.0 / substeps;
  Pose next = pose;
  switch (spec.motion) {
    case PrimitiveMotion::fixed: break;
    case PrimitiveMotion::translate:
      // p' = clamp(p + d)
      next.p = clamp3(pose.p + translation(spec, action, inv_n), spec.lower_bound, spec.upper_bound, nullptr);
      break;
    case PrimitiveMotion::rolling_pin: {
      const RollStep r = roll_step(spec, pose, action, inv_n);
      next.p = clamp3(pose.p + r.t, spec.lower_bound, spec.upper_bound, nullptr);
      // R' = Ry(-dth) R Ry_body(dw)
      next.q = (about_y(-r.dth) * pose.q * about_y(r.dw)).normalized();
      break;
    }
  }
  return next;
}

void advance_pose_adjoint(const PrimitiveSpec& spec, const Pose& pose, const double* action, int substeps,
                          PoseAdjoint& bar, double* action_bar) {
  const double inv_n = 1.0 / substeps;
  switch (spec.motion) {
    case PrimitiveMotion::fixed: break;
    case PrimitiveMotion::translate: {
      Vec3 mask;
      clamp3(pose.p + translation(spec, action, inv_n), spec.lower_bound, spec.upper_bound, &mask);
      const Vec3 pm = mask.cwiseProduct(bar.p);
      for (std::size_t k = 0; k < spec.action_axes.size(); ++k)
        action_bar[k] += spec.action_scale[k] * inv_n * pm[spec.action_axes[k]];
      bar.p = pm;
      break;
    }
    case PrimitiveMotion::rolling_pin: {
      const RollStep r = roll_step(spec, pose, action, inv_n);
      const double dw = r.dw, dth = r.dth;
      const Vec3& u = r.u;
      Vec3 mask;
      clamp3(pose.p + r.t, spec.lower_bound, spec.upper_bound, &mask);
      const Eigen::Quaterniond q_next = (about_y(-dth) * pose.q * about_y(dw)).normalized();
      const Vec3 t_bar = mask.cwiseProduct(bar.p);
      // translation: t = (rr dw u_z, dy, -rr dw u_x)
      double dw_bar = spec.roll_radius * (u.z() * t_bar.x() - u.x() * t_bar.z());
      const double dy_bar = t_bar.y();
      const Vec3 u_bar(-spec.roll_radius * dw * t_bar.z(), 0.0, spec.roll_radius * dw * t_bar.x());
      // rotation: R' = Ry(-dth) R Ry_body(dw): theta_bar = Ry(dth) theta'_bar,
      // dw_bar += (R' e_y) . theta'_bar, dth_bar = -e_y . theta'_bar
      dw_bar += q_next.toRotationMatrix().col(1).dot(bar.theta);
      const double dth_bar = -bar.theta.y();
      // u = -R e_y moves with R: du = dtheta x u, so theta_bar += u x u_bar
      bar.theta = rotation_y(dth) * bar.theta + u.cross(u_bar);
      bar.p = t_bar;
      action_bar[0] += spec.action_scale[0] * inv_n * dw_bar;
      action_bar[1] += spec.action_scale[1] * inv_n * dth_bar;
      action_bar[2] += spec.action_scale[2] * inv_n * dy_bar;
      break;
    }
  }
}

double bounding_radius(const Shape& s) {
  switch (s.kind) {
    case ShapeKind::sphere: return s.radius;
    case ShapeKind::capsule: return s.half_height + s.radius;
    case ShapeKind::cylinder: return std::sqrt(s.radius * s.radius + s.half_height * s.half_height);
    case ShapeKind::torus: return s.major_radius + s.radius;
    case ShapeKind::box: return s.half_extents.norm();
    case ShapeKind::bowl: return s.radius + 0.5 * s.thickness;
  }
  return 0.0;
}

ContactFrame contact_frame(const PrimitiveSpec& spec, const Pose& at_f, const Pose& at_f1, double dt) {
  ContactFrame fr;
  fr.R0 = at_f.q.toRotationMatrix();
  fr.p0 = at_f.p;
  fr.p1 = at_f1.p;
  fr.M = at_f1.q.toRotationMatrix() * fr.R0.transpose();
  fr.inv_dt = 1.0 / dt;
  const double band = spec.softness > 0.0 ? kLn10 / spec.softness : 0.0;
  fr.reach = bounding_radius(spec.shape) + band + 1e-9;
  return fr;
}

namespace {

// The part of collide shared by forward and adjoint: is the node in contact, and how much.
struct ContactState {
  bool active = false;
  double d = 0.0, influence = 0.0;
  Vec3 r, l;  // x - p_f and its local coordinates
};

ContactState contact_state(const PrimitiveSpec& spec, const ContactFrame& fr, const Vec3& x) {
  ContactState c;
  c.r = x - fr.p0;
  if (c.r.squaredNorm() > fr.reach * fr.reach) return c;
  c.l = fr.R0.transpose() * c.r;
  c.d = sdf_distance(spec.shape, c.l);
  if (c.d <= 0.0) {
    c.active = true;
    c.influence = 1.0;  // min(exp(-d softness), 1)
    return c;
  }
  if (spec.softness <= 0.0 || c.d * spec.softness > kLn10 + 1e-9) return c;
  // influence = exp(-d softness), active above 0.1
  c.influence = dm::exp(-c.d * spec.softness);
  c.active = c.influence > 0.1;
  return c;
}

}  // namespace

Vec3 collide(const PrimitiveSpec& spec, const ContactFrame& fr, const Vec3& x, const Vec3& v) {
  const ContactState c = contact_state(spec, fr, x);
  if (!c.active) return v;
  const SdfEval e = evaluate_sdf(spec.shape, c.l);
  const Vec3 n = fr.R0 * e.normal;
  // collider velocity at x: (R_{f+1} R_f^T (x - p_f) + p_{f+1} - x) / dt
  const Vec3 vc = (fr.M * c.r + fr.p1 - x) * fr.inv_dt;
  const Vec3 u = v - vc;
  const double un = u.dot(n);
  Vec3 ut = u;
  if (un < 0.0) {
    // remove the approaching normal part; Coulomb friction shortens the tangential part
    const Vec3 w = u - un * n;
    const double tn = w.norm();
    ut = tn > 1e-30 ? Vec3(w * (std::max(0.0, tn + spec.friction * un) / tn)) : w;
  }
  return vc + (1.0 - c.influence) * u + c.influence * ut;
}

Vec3 collide_adjoint(const PrimitiveSpec& spec, const ContactFrame& fr, const Vec3& x, const Vec3& v, const Vec3& g,
                     PoseAdjoint& at_f, PoseAdjoint& at_f1) {
  const ContactState c = contact_state(spec, fr, x);
  if (!c.active) return g;
  const SdfEval e = evaluate_sdf(spec.shape, c.l);
  const Vec3 n = fr.R0 * e.normal;
  const Vec3 Mr = fr.M * c.r;
  const Vec3 vc = (Mr + fr.p1 - x) * fr.inv_dt;
  const Vec3 u = v - vc;
  const double un = u.dot(n);
  // forward again
  Vec3 ut = u, w = Vec3::Zero();
  double tn = 0.0, scale = 1.0;
  if (un < 0.0) {
    w = u - un * n;
    tn = w.norm();
    scale = tn > 1e-30 ? std::max(0.0, tn + spec.friction * un) / tn : 1.0;
    ut = w * scale;
  }
  // v' = vc + (1 - infl) u + infl ut
  Vec3 vc_bar = g;
  Vec3 u_bar = (1.0 - c.influence) * g;
  const Vec3 ut_bar = c.influence * g;
  const double infl_bar = g.dot(ut - u);
  Vec3 n_bar = Vec3::Zero();
  if (un < 0.0) {
    Vec3 w_bar = Vec3::Zero();
    double un_bar = 0.0;
    if (tn > 1e-30) {
      if (tn + spec.friction * un > 0.0) {
        // ut = w + friction un w / tn
        const double wu = w.dot(ut_bar);
        w_bar = ut_bar * (1.0 + spec.friction * un / tn) - (spec.friction * un * wu / (tn * tn * tn)) * w;
        un_bar = spec.friction * wu / tn;
      }  // else ut = 0: no dependence
    } else {
      w_bar = ut_bar;
    }
    // w = u - un n
    u_bar += w_bar;
    un_bar -= n.dot(w_bar);
    n_bar -= un * w_bar;
    // un = u . n
    u_bar += un_bar * n;
    n_bar += un_bar * u;
  } else {
    u_bar += ut_bar;
  }
  // u = v - vc
  vc_bar -= u_bar;
  // influence = exp(-d softness) where d > 0 (1 otherwise)
  const double d_bar = c.d > 0.0 ? -spec.softness * c.influence * infl_bar : 0.0;
  // vc = (M r + p_{f+1} - x) / dt, r = x - p_f
  const Vec3 vcs = vc_bar * fr.inv_dt;
  at_f1.p += vcs;
  at_f1.theta += Mr.cross(vcs);
  const Vec3 Mt_vcs = fr.M.transpose() * vcs;
  at_f.p -= Mt_vcs;
  at_f.theta -= c.r.cross(Mt_vcs);
  // n = R_f normal(l): theta_bar += n x n_bar; l_bar = H R_f^T n_bar + d_bar normal
  at_f.theta += n.cross(n_bar);
  const Vec3 l_bar = e.hessian * (fr.R0.transpose() * n_bar) + d_bar * e.normal;
  // l = R_f^T (x - p_f)
  const Vec3 Rl = fr.R0 * l_bar;
  at_f.p -= Rl;
  at_f.theta += Rl.cross(c.r);
  return u_bar;
}

double primitive_distance(const PrimitiveSpec& spec, const Pose& pose, const Vec3& x) {
  const Mat3 R = pose.q.toRotationMatrix();
  return sdf_distance(spec.shape, R.transpose() * (x - pose.p));
}

void primitive_distance_adjoint(const PrimitiveSpec& spec, const Pose& pose, const Vec3& x, double d_bar, Vec3& x_bar,
                                PoseAdjoint& pose_bar) {
  const Mat3 R = pose.q.toRotationMatrix();
  const Vec3 r = x - pose.p;
  const SdfEval e = evaluate_sdf(spec.shape, R.transpose() * r);
  const Vec3 Rl = R * (d_bar * e.normal);
  x_bar += Rl;
  pose_bar.p -= Rl;
  pose_bar.theta += Rl.cross(r);
}

}  // namespace dsb::mpm
