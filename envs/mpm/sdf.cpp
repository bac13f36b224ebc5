#include "envs/mpm/sdf.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/error.hpp"
#include "common/number_text.hpp"

namespace dsb::mpm {

namespace {

// Each shape is one function returning the distance; when `out` is given it also writes the
// normal and Hessian there. sdf_distance() and evaluate_sdf() run the same arithmetic for the
// distance, so they agree bit for bit. Hessians are built from explicit outer products a_i a_j
// (commutative, so exactly symmetric) scaled elementwise.

Mat3 outer(const Vec3& a) {
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = a(i) * a(j);
  return m;
}

double norm3(const Vec3& v) { return std::sqrt(v.x() * v.x() + v.y() * v.y() + v.z() * v.z()); }
double norm_xz(const Vec3& v) { return std::sqrt(v.x() * v.x() + v.z() * v.z()); }

// distance to a point, |v| with v = p - point: n = v/|v|, H = (I - n n^T)/|v|.
// At the point itself (|v| = 0): n = `fallback`, H = 0.
void point_derivs(const Vec3& v, double len, const Vec3& fallback, SdfEval* out) {
  if (len > 0.0) {
    out->normal = v / len;
    out->hessian = (Mat3::Identity() - outer(out->normal)) / len;
  } else {
    out->normal = fallback;
    out->hessian.setZero();
  }
}

// distance to the y axis, rho = |p_xz|: n = u = (x, 0, z)/rho, H = (P_xz - u u^T)/rho = t t^T/rho
// with t = (-z, 0, x)/rho the tangent of the circle about y. On the axis: n = +x, H = 0.
void axis_derivs(const Vec3& p, double rho, SdfEval* out) {
  if (rho > 0.0) {
    out->normal = Vec3(p.x() / rho, 0.0, p.z() / rho);
    out->hessian = outer(Vec3(-p.z() / rho, 0.0, p.x() / rho)) / rho;
  } else {
    out->normal = Vec3::UnitX();
    out->hessian.setZero();
  }
}

// Distance to the circle {|p_xz| = a, y = c} about the y axis (torus, cylinder rim, bowl rim).
// In the half-plane of p, q = (rho - a, y - c), d = |q|, m = q/d: n = m0 u + m1 e_y. By the chain
// rule through q: H = m0 Hess(rho) + J^T (I - m m^T) J / d with J = [u^T; e_y^T], i.e.
// H = m0 t t^T / rho + v v^T / d, v = m1 u - m0 e_y the in-plane unit vector normal to n.
// On the axis (rho = 0): u = +x and the t t^T/rho term is dropped. On the circle (d = 0):
// m = (1, 0) (n = u) and the v v^T/d term is dropped.
double circle_distance(const Vec3& p, double a, double c, SdfEval* out) {
  const double rho = norm_xz(p);
  const double q0 = rho - a, q1 = p.y() - c;
  const double d = std::sqrt(q0 * q0 + q1 * q1);
  if (out) {
    Vec3 u = Vec3::UnitX();
    out->hessian.setZero();
    if (rho > 0.0) u = Vec3(p.x() / rho, 0.0, p.z() / rho);
    double m0 = 1.0, m1 = 0.0;
    if (d > 0.0) {
      m0 = q0 / d;
      m1 = q1 / d;
      out->hessian = outer(m1 * u - m0 * Vec3::UnitY()) / d;
    }
    if (rho > 0.0) out->hessian += outer(Vec3(-p.z() / rho, 0.0, p.x() / rho)) * (m0 / rho);
    out->normal = m0 * u + m1 * Vec3::UnitY();
  }
  return d;
}

/* sphere: d = |p| - r; the point-distance form. Centre: n = +y, H = 0. */
double sphere(const Shape& s, const Vec3& p, SdfEval* out) {
  const double len = norm3(p);
  if (out) point_derivs(p, len, Vec3::UnitY(), out);
  return len - s.radius;
}

/* capsule: distance to the segment {(0, y, 0) : |y| <= h} minus r. Beside the segment
   (|y| <= h) it is the distance to the y axis, rho - r (axis form); beyond an end it is the
   distance to the end point (0, +-h, 0) (point form). On the segment: n = +x, H = 0. */
double capsule(const Shape& s, const Vec3& p, SdfEval* out) {
  const double h = s.half_height;
  if (std::abs(p.y()) <= h) {
    const double rho = norm_xz(p);
    if (out) axis_derivs(p, rho, out);
    return rho - s.radius;
  }
  const Vec3 v(p.x(), p.y() - (p.y() >= 0.0 ? h : -h), p.z());
  const double len = norm3(v);
  if (out) point_derivs(v, len, p.y() >= 0.0 ? Vec3::UnitY() : Vec3(-Vec3::UnitY()), out);
  return len - s.radius;
}

/* cylinder (axis y, radius r, half height h), the exact SDF: d = (rho - r, |y| - h),
   sdf = min(max(d0, d1), 0) + |max(d, 0)|. Outside both slabs (d0, d1 > 0) it is the distance
   to the rim circle (circle form); otherwise max(d0, d1): the side (axis form, H = t t^T/rho)
   when d0 > d1, else the cap plane (n = sign(y) e_y, H = 0; sign(0) = +1). Inside on the axis
   (only when the side is nearer than the caps): n = +x, H = 0. */
double cylinder(const Shape& s, const Vec3& p, SdfEval* out) {
  const double rho = norm_xz(p);
  const double d0 = rho - s.radius, d1 = std::abs(p.y()) - s.half_height;
  const double sgn = p.y() >= 0.0 ? 1.0 : -1.0;
  if (d0 > 0.0 && d1 > 0.0) return circle_distance(p, s.radius, sgn * s.half_height, out);
  if (d0 > d1) {
    if (out) axis_derivs(p, rho, out);
    return d0;
  }
  if (out) {
    out->normal = Vec3(0.0, sgn, 0.0);
    out->hessian.setZero();
  }
  return d1;
}

/* torus (axis y, major radius R in xz, tube radius r): |(rho - R, y)| - r, the distance to the
   tube's centre circle (circle form) minus r. On the axis: u = +x; on the centre circle: n = u. */
double torus(const Shape& s, const Vec3& p, SdfEval* out) {
  return circle_distance(p, s.major_radius, 0.0, out) - s.radius;
}

/* box (half extents b), the exact SDF with q = |p| - b and s = sign(p) componentwise
   (sign(0) = +1). At most one q_i > 0 (inside, on the surface, or facing one face):
   d = max_i q_i, n = s_k e_k for the first maximal k, H = 0 (planar). Two or three q_i > 0
   (facing an edge or a corner): the distance to that edge line or corner point,
   v = s * max(q, 0), d = |v|, n = v/d, H = (P - n n^T)/d with P = diag(q_i > 0) the projector
   off the edge direction. */
double box(const Shape& s, const Vec3& p, SdfEval* out) {
  Vec3 q, sg, v;
  int positive = 0, k = 0;
  for (int i = 0; i < 3; ++i) {
    q(i) = std::abs(p(i)) - s.half_extents(i);
    sg(i) = p(i) >= 0.0 ? 1.0 : -1.0;
    v(i) = sg(i) * std::max(q(i), 0.0);
    if (q(i) > 0.0) ++positive;
    if (q(i) > q(k)) k = i;
  }
  if (positive <= 1) {
    if (out) {
      out->normal = sg(k) * Vec3::Unit(k);
      out->hessian.setZero();
    }
    return q(k);
  }
  const double d = norm3(v);
  if (out) {
    if (d > 0.0) {  // d > 0 unless the squares underflow
      out->normal = v / d;
      Mat3 proj = Mat3::Zero();
      for (int i = 0; i < 3; ++i) proj(i, i) = q(i) > 0.0 ? 1.0 : 0.0;
      out->hessian = (proj - outer(out->normal)) / d;
    } else {
      out->normal = sg(k) * Vec3::Unit(k);
      out->hessian.setZero();
    }
  }
  return d;
}

/* bowl: the spherical cap {|x| = R, y <= c} thickened by t/2 (sdf = distance to the cap - t/2).
   In the half-plane (rho, y) the rim is at (w, c), w = sqrt(R^2 - c^2). p . x over the cap is
   largest at R p/|p| when that point is on the cap (the direction of p is not above the rim's,
   c rho >= w y): the distance is ||p| - R| (point form times sign(|p| - R):
   H = sign (I - n n^T)/|p|, sign(0) = +1). Otherwise the maximum lies on the rim circle, at the
   rim point of p's azimuth: the distance to the rim circle (circle form; on the axis above:
   u = +x). The distance is C1 across the two regions. Centre: n = +y, H = 0. */
double bowl(const Shape& s, const Vec3& p, SdfEval* out) {
  const double c = s.rim_height, w = std::sqrt(s.radius * s.radius - c * c);
  const double half_t = 0.5 * s.thickness;
  if (c * norm_xz(p) < w * p.y()) return circle_distance(p, w, c, out) - half_t;
  const double len = norm3(p);
  const double e = len - s.radius;
  if (out) {
    const double sgn = e >= 0.0 ? 1.0 : -1.0;
    point_derivs(p, len, -Vec3::UnitY(), out);
    out->normal *= sgn;
    out->hessian *= sgn;
  }
  return std::abs(e) - half_t;
}

double dispatch(const Shape& s, const Vec3& p, SdfEval* out) {
  switch (s.kind) {
    case ShapeKind::sphere: return sphere(s, p, out);
    case ShapeKind::capsule: return capsule(s, p, out);
    case ShapeKind::cylinder: return cylinder(s, p, out);
    case ShapeKind::torus: return torus(s, p, out);
    case ShapeKind::box: return box(s, p, out);
    case ShapeKind::bowl: return bowl(s, p, out);
  }
  throw std::invalid_argument("evaluate_sdf: unknown ShapeKind");
}

void require(bool ok, const Shape& s, const char* field, const std::string& rule, double got) {
  if (!ok)
    throw ConfigError("shape", field,
                      "must be " + rule + " for a " + shape_kind_name(s.kind) + ", got " + number_text(got));
}

void require_positive(const Shape& s, const char* field, double x) {
  require(std::isfinite(x) && x > 0.0, s, field, "finite and > 0", x);
}

}  // namespace

const char* shape_kind_name(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::sphere: return "sphere";
    case ShapeKind::capsule: return "capsule";
    case ShapeKind::cylinder: return "cylinder";
    case ShapeKind::torus: return "torus";
    case ShapeKind::box: return "box";
    case ShapeKind::bowl: return "bowl";
  }
  return "unknown";
}

void Shape::validate() const {
  switch (kind) {
    case ShapeKind::sphere: require_positive(*this, "radius", radius); return;
    case ShapeKind::capsule:
      require_positive(*this, "radius", radius);
      require(std::isfinite(half_height) && half_height >= 0.0, *this, "half_height", "finite and >= 0", half_height);
      return;
    case ShapeKind::cylinder:
      require_positive(*this, "radius", radius);
      require_positive(*this, "half_height", half_height);
      return;
    case ShapeKind::torus:
      require_positive(*this, "major_radius", major_radius);
      require_positive(*this, "radius", radius);
      require(radius <= major_radius, *this, "radius", "<= major_radius (" + number_text(major_radius) + ")", radius);
      return;
    case ShapeKind::box:
      require_positive(*this, "half_extents.x", half_extents.x());
      require_positive(*this, "half_extents.y", half_extents.y());
      require_positive(*this, "half_extents.z", half_extents.z());
      return;
    case ShapeKind::bowl: {
      require_positive(*this, "radius", radius);
      require(std::isfinite(rim_height) && std::abs(rim_height) < radius, *this, "rim_height",
              "in (-radius, radius) = (" + number_text(-radius) + ", " + number_text(radius) + ")", rim_height);
      require_positive(*this, "thickness", thickness);
      const double w = std::sqrt(radius * radius - rim_height * rim_height);
      require(thickness <= 2.0 * w, *this, "thickness", "<= 2 sqrt(radius^2 - rim_height^2) = " + number_text(2.0 * w),
              thickness);
      return;
    }
  }
  throw ConfigError("shape", "kind",
                    "is not a known shape kind, got " + number_text(static_cast<double>(static_cast<int>(kind))));
}

SdfEval evaluate_sdf(const Shape& shape, const Vec3& p_local) {
  SdfEval r;
  r.distance = dispatch(shape, p_local, &r);
  return r;
}

double sdf_distance(const Shape& shape, const Vec3& p_local) { return dispatch(shape, p_local, nullptr); }

}  // namespace dsb::mpm
