#include "envs/rigid/contact.hpp"

#include <cmath>

namespace dsb {

template <int D>
ContactGeometry<D> plane_geometry(const Eigen::Matrix<double, D, 1>& p, const Eigen::Matrix<double, D, 1>& normal,
                                  double offset) {
  // signed distance d = n . p - offset; the normal is constant (dn/dp = 0)
  ContactGeometry<D> g;
  g.distance = normal.dot(p) - offset;
  g.normal = normal;
  return g;
}

ContactGeometry<2> capsule_geometry(const Eigen::Vector2d& p, const Eigen::Vector2d& centre,
                                    const Eigen::Vector2d& axis, double half_length, double radius) {
  ContactGeometry<2> g;
  // closest point on the segment: q = centre + s axis, s = clamp((p - centre) . axis, -h, h)
  const Eigen::Vector2d rel = p - centre;
  double s = rel.dot(axis);
  bool end_cap = false;
  if (s > half_length) {
    s = half_length;
    end_cap = true;
  } else if (s < -half_length) {
    s = -half_length;
    end_cap = true;
  }
  const Eigen::Vector2d r = rel - s * axis;
  const double len = r.norm();
  if (!(len > 0.0)) {
    // centre exactly on the segment (deep inside the paddle): push out along the paddle's
    // left-hand normal (-sin a, cos a), a choice of ours for a measure-zero case
    g.distance = -radius;
    g.normal = Eigen::Vector2d(-axis.y(), axis.x());
    return g;
  }
  // d = |p - q| - radius, n = (p - q) / |p - q|
  g.distance = len - radius;
  g.normal = r / len;
  // dn/dp = (I - n n^T) dr/dp / |r|: on the flat faces dr/dp = I - axis axis^T = n n^T, so
  // dn/dp = 0 (in 2-D); on the rounded ends q is fixed, dr/dp = I
  if (end_cap) g.dnormal_dx = (Eigen::Matrix2d::Identity() - g.normal * g.normal.transpose()) / len;
  return g;
}

template <int D>
ContactForce<D> contact_force(const ContactConfig& cfg, double ball_radius, const ContactGeometry<D>& g,
                              const Eigen::Matrix<double, D, 1>& v) {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Row = Eigen::Matrix<double, 1, D>;
  using Mat = Eigen::Matrix<double, D, D>;
  ContactForce<D> out;
  // penetration c = max(0, r - d): the contact acts only while c > 0 (dc/dp = -n^T)
  const double c = ball_radius - g.distance;
  if (!(c > 0.0)) return out;
  const Vec& n = g.normal;
  const Mat& dn = g.dnormal_dx;
  // normal velocity v_n = v . n; dv_n/dp = v^T dn/dp, dv_n/dv = n^T
  const double vn = v.dot(n);
  const Row dvn_dx = v.transpose() * dn;
  // normal force f_n = ke c - kd min(v_n, 0), damping only on approach (v_n < 0)
  const bool damping = vn < 0.0;
  const double fn = cfg.ke * c - (damping ? cfg.kd * vn : 0.0);
  // never pulling: f_n = max(0, .) (with c > 0 both terms are >= 0, kept as a guard)
  if (!(fn > 0.0)) return out;
  Row dfn_dx = -cfg.ke * n.transpose();
  Row dfn_dv = Row::Zero();
  if (damping) {
    dfn_dx -= cfg.kd * dvn_dx;
    dfn_dv = -cfg.kd * n.transpose();
  }
  out.active = true;
  out.penetration = c;
  out.normal_force = fn;
  // normal part f_n n: d/dp = n df_n/dp + f_n dn/dp, d/dv = n df_n/dv
  out.f = fn * n;
  out.df_dx = n * dfn_dx + fn * dn;
  out.df_dv = n * dfn_dv;
  if (cfg.mu > 0.0) {
    // smooth Coulomb friction f_t = -mu f_n v_t / sqrt(|v_t|^2 + eps^2), v_t = v - v_n n
    const Vec vt = v - vn * n;
    const double s = std::sqrt(vt.squaredNorm() + cfg.friction_smoothing * cfg.friction_smoothing);
    const Vec w = vt / s;
    // dv_t/dv = I - n n^T, dv_t/dp = -(n dv_n/dp + v_n dn/dp); dw/dv_t = (I - w w^T) / s
    const Mat dvt_dv = Mat::Identity() - n * n.transpose();
    const Mat dvt_dx = -(n * dvn_dx + vn * dn);
    const Mat dw_dvt = (Mat::Identity() - w * w.transpose()) / s;
    out.f -= cfg.mu * fn * w;
    out.df_dx -= cfg.mu * (w * dfn_dx + fn * (dw_dvt * dvt_dx));
    out.df_dv -= cfg.mu * (w * dfn_dv + fn * (dw_dvt * dvt_dv));
  }
  return out;
}

template ContactGeometry<2> plane_geometry<2>(const Eigen::Vector2d&, const Eigen::Vector2d&, double);
template ContactGeometry<3> plane_geometry<3>(const Eigen::Vector3d&, const Eigen::Vector3d&, double);
template ContactForce<2> contact_force<2>(const ContactConfig&, double, const ContactGeometry<2>&,
                                          const Eigen::Vector2d&);
template ContactForce<3> contact_force<3>(const ContactConfig&, double, const ContactGeometry<3>&,
                                          const Eigen::Vector3d&);

}  // namespace dsb
