// MPM rigid primitives' SDFs (envs/mpm/sdf): closed-form distances, distance against brute force
// over a dense surface sampling, normal and Hessian against central differences, the cheap path's
// bits, finite values at degenerate points, validate().
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "common/det_math.hpp"
#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/mpm/sdf.hpp"
#include "support/config_error.hpp"

namespace dsb::mpm {
namespace {

constexpr double kPi = std::numbers::pi;

// shapes by their fields (Shape is an aggregate: the fields not named keep their defaults)
Shape sphere(double r) { return {.kind = ShapeKind::sphere, .radius = r}; }
Shape capsule(double r, double h) { return {.kind = ShapeKind::capsule, .radius = r, .half_height = h}; }
Shape cylinder(double r, double h) { return {.kind = ShapeKind::cylinder, .radius = r, .half_height = h}; }
Shape torus(double major, double r) { return {.kind = ShapeKind::torus, .radius = r, .major_radius = major}; }
Shape box(double x, double y, double z) { return {.kind = ShapeKind::box, .half_extents = Vec3(x, y, z)}; }
Shape bowl(double r, double thickness, double rim_height) {
  return {.kind = ShapeKind::bowl, .radius = r, .thickness = thickness, .rim_height = rim_height};
}

// the shapes every randomized test runs on (extent: half size of a box holding the shape)
struct Case {
  std::string name;
  Shape shape;
  double extent;
};
std::vector<Case> cases() {
  return {{"sphere", sphere(0.5), 0.5},
          {"capsule", capsule(0.2, 0.6), 0.8},
          {"cylinder", cylinder(0.4, 0.3), 0.4},
          {"torus", torus(0.6, 0.15), 0.75},
          {"horn torus", torus(0.3, 0.3), 0.6},
          {"box", box(0.5, 0.2, 0.35), 0.5},
          {"hemisphere bowl", bowl(0.5, 0.06, 0.0), 0.55},
          {"deep bowl", bowl(0.5, 0.06, 0.3), 0.55},
          {"shallow bowl", bowl(0.5, 0.04, -0.35), 0.55}};
}

double rim_w(const Shape& s) { return std::sqrt(s.radius * s.radius - s.rim_height * s.rim_height); }

// ---- dense surface samplings --------------------------------------------------------------

// Points of patches x(u, v) on grids including their ends. With |dx/du| <= lu, |dx/dv| <= lv, every
// point of a patch is within lu du/2 + lv dv/2 of a grid node (move along u, then along v).
struct Sampling {
  std::vector<Vec3> points;
  double cover = 0.0;  // every surface point lies within `cover` of a sample

  template <class F>
  void patch(double u0, double u1, double lu, double v0, double v1, double lv, F f) {
    constexpr double kDensity = 250.0;  // grid nodes per unit of arc length
    const int nu = std::max(2, static_cast<int>(std::ceil((u1 - u0) * lu * kDensity)) + 1);
    const int nv = std::max(2, static_cast<int>(std::ceil((v1 - v0) * lv * kDensity)) + 1);
    const double du = (u1 - u0) / (nu - 1), dv = (v1 - v0) / (nv - 1);
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) points.push_back(f(u0 + du * i, v0 + dv * j));
    cover = std::max(cover, 0.5 * (lu * du + lv * dv));
  }

  // a surface of revolution about y from a profile curve (rho(u), y(u)) with |d(rho, y)/du| <= lu
  template <class F>
  void revolve(double u0, double u1, double lu, double rho_max, F profile) {
    patch(u0, u1, lu, 0.0, 2.0 * kPi, rho_max, [&](double u, double phi) {
      const auto [rho, y] = profile(u);
      return Vec3(rho * dm::cos(phi), y, rho * dm::sin(phi));
    });
  }

  double min_distance(const Vec3& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3& x : points) best = std::min(best, (p - x).squaredNorm());
    return std::sqrt(best);
  }
};

struct RhoY {
  double rho, y;
};

// the surface of the solid (for the bowl: of the thickened shell)
Sampling surface_of(const Shape& s) {
  Sampling out;
  const double r = s.radius, h = s.half_height;
  switch (s.kind) {
    case ShapeKind::sphere:
      out.revolve(0.0, kPi, r, r, [&](double a) { return RhoY{r * dm::sin(a), r * dm::cos(a)}; });
      break;
    case ShapeKind::capsule:
      out.revolve(-h, h, 1.0, r, [&](double y) { return RhoY{r, y}; });
      out.revolve(0.0, kPi / 2, r, r, [&](double a) { return RhoY{r * dm::sin(a), h + r * dm::cos(a)}; });
      out.revolve(kPi / 2, kPi, r, r, [&](double a) { return RhoY{r * dm::sin(a), -h + r * dm::cos(a)}; });
      break;
    case ShapeKind::cylinder:
      out.revolve(-h, h, 1.0, r, [&](double y) { return RhoY{r, y}; });
      out.revolve(0.0, r, 1.0, r, [&](double rho) { return RhoY{rho, h}; });
      out.revolve(0.0, r, 1.0, r, [&](double rho) { return RhoY{rho, -h}; });
      break;
    case ShapeKind::torus: {
      const double big = s.major_radius;
      out.revolve(0.0, 2.0 * kPi, r, big + r, [&](double a) { return RhoY{big + r * dm::cos(a), r * dm::sin(a)}; });
      break;
    }
    case ShapeKind::box:
      for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        const Vec3& e = s.half_extents;
        for (double sign : {-1.0, 1.0})
          out.patch(-e(a), e(a), 1.0, -e(b), e(b), 1.0, [&](double u, double v) {
            Vec3 x;
            x(axis) = sign * e(axis);
            x(a) = u;
            x(b) = v;
            return x;
          });
      }
      break;
    case ShapeKind::bowl: {
      // outer and inner caps (polar angle from -y up to the rim's), and the rim's half tube
      const double c = s.rim_height, w = rim_w(s), ht = 0.5 * s.thickness;
      const double alpha_max = dm::acos(-c / r), gamma = dm::atan2(c, w);
      for (double rr : {r + ht, r - ht})
        out.revolve(0.0, alpha_max, rr, rr, [&](double a) { return RhoY{rr * dm::sin(a), -rr * dm::cos(a)}; });
      out.revolve(gamma, gamma + kPi, ht, w + ht, [&](double b) {
        return RhoY{w + ht * dm::cos(b), c + ht * dm::sin(b)};
      });
      break;
    }
  }
  return out;
}

// the bowl's spherical cap (the mid-surface, before thickening)
Sampling bowl_cap(const Shape& s) {
  Sampling out;
  const double r = s.radius;
  out.revolve(0.0, dm::acos(-s.rim_height / r), r, r, [&](double a) { return RhoY{r * dm::sin(a), -r * dm::cos(a)}; });
  return out;
}

// an inside test written independently of the SDF formulas (not for the bowl)
bool inside(const Shape& s, const Vec3& p) {
  const double x = p.x(), y = p.y(), z = p.z(), r = s.radius, h = s.half_height;
  switch (s.kind) {
    case ShapeKind::sphere: return p.squaredNorm() < r * r;
    case ShapeKind::capsule: {
      const double yc = std::clamp(y, -h, h);
      return x * x + (y - yc) * (y - yc) + z * z < r * r;
    }
    case ShapeKind::cylinder: return x * x + z * z < r * r && std::abs(y) < h;
    case ShapeKind::torus: {  // the quartic (|p|^2 + R^2 - r^2)^2 < 4 R^2 (x^2 + z^2)
      const double big = s.major_radius, k = p.squaredNorm() + big * big - r * r;
      return k * k < 4.0 * big * big * (x * x + z * z);
    }
    case ShapeKind::box: return (p.cwiseAbs().array() < s.half_extents.array()).all();
    case ShapeKind::bowl: break;
  }
  ADD_FAILURE() << "no inside test for this shape";
  return false;
}

// random points: half uniform in a box 1.5x the shape's, half near random surface samples
std::vector<Vec3> random_points(Rng& rng, const Sampling& surface, double extent, int n) {
  std::vector<Vec3> pts;
  auto cube = [&](double half) {
    return Vec3(rng.uniform(-half, half), rng.uniform(-half, half), rng.uniform(-half, half));
  };
  for (int i = 0; i < n; ++i) {
    if (i % 2 == 0)
      pts.push_back(cube(1.5 * extent));
    else
      pts.push_back(surface.points[rng.below(surface.points.size())] + cube(0.05 * extent));
  }
  return pts;
}

// ---- closed forms ---------------------------------------------------------------------------

void expect_distance(const Shape& s, const Vec3& p, double expected) {
  EXPECT_NEAR(evaluate_sdf(s, p).distance, expected, 1e-15)
      << shape_kind_name(s.kind) << " at (" << p.transpose() << ")";
}

TEST(MpmSdf, ClosedFormsSphereCapsuleCylinder) {
  const Shape sp = sphere(0.5);
  expect_distance(sp, Vec3::Zero(), -0.5);
  expect_distance(sp, Vec3(0.5, 0.0, 0.0), 0.0);
  expect_distance(sp, Vec3(0.0, 0.0, -0.5), 0.0);
  expect_distance(sp, Vec3(0.0, 2.0, 0.0), 1.5);
  expect_distance(sp, Vec3(0.6, 0.0, 0.8), 0.5);
  expect_distance(sp, Vec3(-0.1, 0.2, 0.2), -0.2);

  const Shape ca = capsule(0.25, 1.0);
  expect_distance(ca, Vec3::Zero(), -0.25);
  expect_distance(ca, Vec3(0.0, 1.0, 0.0), -0.25);                 // segment end
  expect_distance(ca, Vec3(0.0, 2.0, 0.0), 0.75);                  // on the axis beyond the end
  expect_distance(ca, Vec3(0.0, -1.25, 0.0), 0.0);                 // bottom pole
  expect_distance(ca, Vec3(1.0, 0.5, 0.0), 0.75);                  // beside the segment
  expect_distance(ca, Vec3(0.0, -0.9, 0.25), 0.0);                 // on the side
  expect_distance(ca, Vec3(0.3, 1.4, 0.0), 0.25);                  // beyond the end: |(0.3, 0.4)| - 0.25
  expect_distance(capsule(0.25, 0.0), Vec3(0.0, 0.0, 1.0), 0.75);  // h = 0: a sphere

  const Shape cy = cylinder(0.5, 1.0);
  expect_distance(cy, Vec3::Zero(), -0.5);
  expect_distance(cy, Vec3(0.0, 0.8, 0.0), -0.2);  // on the axis near the cap
  expect_distance(cy, Vec3(0.0, -0.9, 0.0), -0.1);
  expect_distance(cy, Vec3(0.0, 3.0, 0.0), 2.0);   // above the cap
  expect_distance(cy, Vec3(0.0, 0.0, -2.0), 1.5);  // beside the side
  expect_distance(cy, Vec3(0.8, 1.4, 0.0), 0.5);   // outside the rim: |(0.3, 0.4)|
  expect_distance(cy, Vec3(0.0, -1.4, -0.8), 0.5);
  expect_distance(cy, Vec3(0.5, 1.0, 0.0), 0.0);          // on the rim
  expect_distance(cy, Vec3(0.3, 0.0, 0.4), 0.0);          // on the side
  expect_distance(cy, Vec3(0.0, -1.004, -0.503), 0.005);  // just outside the rim: |(3, 4)| 1e-3
  expect_distance(cy, Vec3(0.503, 0.9, 0.0), 0.003);      // just outside the side, below the rim
}

TEST(MpmSdf, ClosedFormsTorusBoxBowl) {
  const Shape to = torus(1.0, 0.25);
  expect_distance(to, Vec3::Zero(), 0.75);          // centre: R - r
  expect_distance(to, Vec3(1.0, 0.0, 0.0), -0.25);  // on the tube circle
  expect_distance(to, Vec3(0.0, 0.0, -1.0), -0.25);
  expect_distance(to, Vec3(1.25, 0.0, 0.0), 0.0);
  expect_distance(to, Vec3(0.0, 0.0, 0.75), 0.0);  // inner equator
  expect_distance(to, Vec3(2.0, 0.0, 0.0), 0.75);
  expect_distance(to, Vec3(0.0, 1.0, 0.0), std::sqrt(2.0) - 0.25);  // on the axis
  expect_distance(to, Vec3(0.6, 0.4, -0.8), 0.15);                  // rho = 1, y = 0.4: |(0, 0.4)| - r
  expect_distance(torus(0.5, 0.5), Vec3::Zero(), 0.0);              // horn torus: the centre is on it

  const Shape bx = box(1.0, 2.0, 3.0);
  expect_distance(bx, Vec3::Zero(), -1.0);
  expect_distance(bx, Vec3(0.5, 0.0, 0.0), -0.5);
  expect_distance(bx, Vec3(0.0, -1.5, 2.9), -0.1);
  expect_distance(bx, Vec3(1.0, 2.0, 3.0), 0.0);  // corner
  expect_distance(bx, Vec3(-1.0, 2.0, -3.0), 0.0);
  expect_distance(bx, Vec3(0.0, 0.0, 5.0), 2.0);              // facing a face
  expect_distance(bx, Vec3(-2.0, 3.0, 0.0), std::sqrt(2.0));  // facing an edge
  expect_distance(bx, Vec3(2.0, -3.0, 4.0), std::sqrt(3.0));  // facing a corner
  expect_distance(bx, Vec3(1.3, 2.4, 0.0), 0.5);              // edge: |(0.3, 0.4)|
  expect_distance(bx, Vec3(1.003, -2.004, 1.0), 0.005);       // just outside an edge
  expect_distance(bx, Vec3(1.002, -2.003, 3.006),
                  0.007);  // just outside a corner: |(2, 3, 6)| 1e-3

  const Shape hemi = bowl(1.0, 0.1, 0.0);
  expect_distance(hemi, Vec3::Zero(), 0.95);           // centre: R - t/2
  expect_distance(hemi, Vec3(0.0, -1.0, 0.0), -0.05);  // bottom of the mid-surface
  expect_distance(hemi, Vec3(0.0, -1.05, 0.0), 0.0);   // outer surface
  expect_distance(hemi, Vec3(0.0, -2.0, 0.0), 0.95);
  expect_distance(hemi, Vec3(1.0, 0.0, 0.0), -0.05);                  // rim
  expect_distance(hemi, Vec3(2.0, 0.0, 0.0), 0.95);                   // beside the rim, level with it
  expect_distance(hemi, Vec3(0.0, 1.0, 0.0), std::sqrt(2.0) - 0.05);  // on the axis above
  expect_distance(hemi, Vec3(1.0, 1.0, 0.0), 0.95);                   // above the rim
  expect_distance(hemi, Vec3(0.0, 0.5, -1.0), 0.45);
  const Shape deep = bowl(1.0, 0.1, 0.6);  // rim at (0.8, 0.6)
  expect_distance(deep, Vec3::Zero(), 0.95);
  expect_distance(deep, Vec3(0.0, 0.0, 1.0), -0.05);  // the equator is on the cap
  expect_distance(deep, Vec3(1.1, 1.0, 0.0), 0.45);   // rim + (0.3, 0.4)
  expect_distance(deep, Vec3(0.0, 0.6, 0.0), 0.75);   // axis at rim height: w - t/2
  const Shape shallow = bowl(1.0, 0.1, -0.6);         // rim at (0.8, -0.6)
  expect_distance(shallow, Vec3::Zero(), 0.95);       // the rim is as far as the cap
  expect_distance(shallow, Vec3(0.0, 0.0, 1.0), std::sqrt(0.04 + 0.36) - 0.05);
  expect_distance(shallow, Vec3(0.0, -1.0, 0.0), -0.05);
}

// ---- distance against brute force -------------------------------------------------------------

// The exact distance is at most the distance to any surface sample and at least that minus the
// sampling's cover radius. Reports the largest (brute - exact) gap.
TEST(MpmSdf, DistanceMatchesBruteForceOverADenseSurfaceSampling) {
  Rng rng(20240611);
  for (const Case& c : cases()) {
    const Sampling surface = surface_of(c.shape);
    const bool is_bowl = c.shape.kind == ShapeKind::bowl;
    const Sampling cap = is_bowl ? bowl_cap(c.shape) : Sampling{};
    double worst_gap = 0.0;
    int signs = 0;
    for (const Vec3& p : random_points(rng, surface, c.extent, 240)) {
      const double d = sdf_distance(c.shape, p), brute = surface.min_distance(p);
      EXPECT_LE(std::abs(d), brute + 1e-12) << c.name << " at (" << p.transpose() << ")";
      EXPECT_GE(std::abs(d), brute - surface.cover - 1e-12) << c.name << " at (" << p.transpose() << ")";
      worst_gap = std::max(worst_gap, brute - std::abs(d));
      if (std::abs(d) < 1e-9) continue;
      bool in;
      if (is_bowl) {  // inside the wall: within t/2 of the cap
        const double dc = cap.min_distance(p), ht = 0.5 * c.shape.thickness;
        if (std::abs(dc - ht) <= cap.cover) continue;
        in = dc < ht;
      } else {
        in = inside(c.shape, p);
      }
      ++signs;
      EXPECT_EQ(d < 0.0, in) << c.name << " sign at (" << p.transpose() << "), d = " << d;
    }
    std::printf("[ brute    ] %-16s %7zu samples, cover %.4f, worst gap %.4f, %d signs\n", c.name.c_str(),
                surface.points.size(), surface.cover, worst_gap, signs);
  }
}

// The bowl is the cap thickened by t/2: sdf + t/2 is the exact distance to the cap itself.
TEST(MpmSdf, BowlIsTheDistanceToItsSphericalCap) {
  Rng rng(77);
  for (const Case& c : cases()) {
    if (c.shape.kind != ShapeKind::bowl) continue;
    const Sampling cap = bowl_cap(c.shape);
    double worst_gap = 0.0;
    for (const Vec3& p : random_points(rng, cap, c.extent, 400)) {
      const double d = sdf_distance(c.shape, p) + 0.5 * c.shape.thickness;
      const double brute = cap.min_distance(p);
      EXPECT_LE(d, brute + 1e-12) << c.name << " at (" << p.transpose() << ")";
      EXPECT_GE(d, brute - cap.cover - 1e-12) << c.name << " at (" << p.transpose() << ")";
      worst_gap = std::max(worst_gap, brute - d);
    }
    std::printf("[ cap      ] %-16s %7zu samples, cover %.4f, worst gap %.4f\n", c.name.c_str(), cap.points.size(),
                cap.cover, worst_gap);
  }
}

// ---- derivatives ------------------------------------------------------------------------------

// true when p is within m of a set where the distance's gradient or Hessian is discontinuous
// (medial axes, region boundaries) or its curvature is large (axes, centres)
bool near_nonsmooth(const Shape& s, const Vec3& p, double m) {
  const double rho = std::sqrt(p.x() * p.x() + p.z() * p.z()), len = p.norm();
  const double r = s.radius, h = s.half_height;
  switch (s.kind) {
    case ShapeKind::sphere: return len < m;
    case ShapeKind::capsule: return rho < m || std::abs(std::abs(p.y()) - h) < m;
    case ShapeKind::cylinder: {
      const double d0 = rho - r, d1 = std::abs(p.y()) - h;
      return std::min({std::abs(d0), std::abs(d1), std::abs(d0 - d1), std::abs(p.y()), rho}) < m;
    }
    case ShapeKind::torus:
      return rho < m || std::sqrt((rho - s.major_radius) * (rho - s.major_radius) + p.y() * p.y()) < m;
    case ShapeKind::box: {
      const Vec3 q = p.cwiseAbs() - s.half_extents;
      for (int i = 0; i < 3; ++i)
        if (std::abs(q(i)) < m || std::abs(p(i)) < m || std::abs(q(i) - q((i + 1) % 3)) < m) return true;
      return false;
    }
    case ShapeKind::bowl: {
      const double c = s.rim_height, w = rim_w(s);
      return len < m || rho < m || std::abs(len - r) < m || std::abs(c * rho - w * p.y()) / r < m;
    }
  }
  return true;
}

TEST(MpmSdf, NormalIsTheGradientAndHessianItsJacobian) {
  constexpr double kStep = 1e-6, kMargin = 1e-2;
  Rng rng(31337);
  for (const Case& c : cases()) {
    const Sampling surface = surface_of(c.shape);
    double worst_grad = 0.0, worst_hess = 0.0, worst_unit = 0.0, worst_hn = 0.0;
    int checked = 0, skipped = 0;
    for (const Vec3& p : random_points(rng, surface, c.extent, 400)) {
      if (near_nonsmooth(c.shape, p, kMargin)) {
        ++skipped;
        continue;
      }
      ++checked;
      const SdfEval e = evaluate_sdf(c.shape, p);
      Vec3 grad;
      Mat3 jac;
      for (int i = 0; i < 3; ++i) {
        Vec3 lo = p, hi = p;
        lo(i) -= kStep;
        hi(i) += kStep;
        grad(i) = (sdf_distance(c.shape, hi) - sdf_distance(c.shape, lo)) / (2.0 * kStep);
        jac.col(i) = (evaluate_sdf(c.shape, hi).normal - evaluate_sdf(c.shape, lo).normal) / (2.0 * kStep);
      }
      const double hmax = e.hessian.cwiseAbs().maxCoeff();
      const double eg = (grad - e.normal).cwiseAbs().maxCoeff();
      const double eh = (jac - e.hessian).cwiseAbs().maxCoeff() / (hmax + 1.0);
      const double eu = std::abs(e.normal.norm() - 1.0);
      const double ehn = (e.hessian * e.normal).cwiseAbs().maxCoeff() / (hmax + 1.0);
      EXPECT_LE(eg, 1e-7) << c.name << " gradient at (" << p.transpose() << ")";
      EXPECT_LE(eh, 1e-6) << c.name << " Hessian at (" << p.transpose() << ")\n" << e.hessian << "\nvs\n" << jac;
      EXPECT_LE(eu, 1e-15) << c.name << " |normal| at (" << p.transpose() << ")";
      EXPECT_LE(ehn, 1e-14) << c.name << " H n at (" << p.transpose() << ")";
      EXPECT_TRUE(e.hessian == e.hessian.transpose()) << c.name << " symmetric at (" << p.transpose() << ")";
      worst_grad = std::max(worst_grad, eg);
      worst_hess = std::max(worst_hess, eh);
      worst_unit = std::max(worst_unit, eu);
      worst_hn = std::max(worst_hn, ehn);
    }
    EXPECT_GE(checked, 200) << c.name;
    std::printf(
        "[ derivs   ] %-16s %3d points (%2d skipped): gradient %.1e, Hessian %.1e, "
        "|n|-1 %.1e, Hn %.1e\n",
        c.name.c_str(), checked, skipped, worst_grad, worst_hess, worst_unit, worst_hn);
  }
}

// ---- cheap path, degenerate points, validate ----------------------------------------------------

std::vector<Vec3> degenerate_points(const Shape& s) {
  const double r = s.radius, h = s.half_height;
  std::vector<Vec3> pts = {Vec3::Zero(),         Vec3(0.0, 0.3, 0.0),    Vec3(0.0, -0.3, 0.0),     Vec3(0.0, 2.0, 0.0),
                           Vec3(0.0, -2.0, 0.0), Vec3(1e-300, 0.0, 0.0), Vec3(0.0, 1e-170, 1e-170)};
  switch (s.kind) {
    case ShapeKind::capsule:
      for (double y : {-h, h, 0.5 * h, std::nextafter(h, 2.0)}) pts.push_back(Vec3(0.0, y, 0.0));
      break;
    case ShapeKind::cylinder:
      for (double y : {-h, h, h - r, h - 0.5 * r}) pts.push_back(Vec3(0.0, y, 0.0));
      pts.push_back(Vec3(r, h, 0.0));
      pts.push_back(Vec3(0.0, -h, -r));
      break;
    case ShapeKind::torus:
      pts.push_back(Vec3(s.major_radius, 0.0, 0.0));
      pts.push_back(Vec3(0.0, 0.0, -s.major_radius));
      break;
    case ShapeKind::box: {
      const Vec3& b = s.half_extents;
      for (double sx : {-1.0, 1.0})
        for (double sy : {-1.0, 1.0})
          for (double sz : {-1.0, 1.0}) pts.push_back(Vec3(sx * b.x(), sy * b.y(), sz * b.z()));
      pts.push_back(Vec3(b.x(), b.y(), 0.0));
      break;
    }
    case ShapeKind::bowl: {
      const double w = rim_w(s), c = s.rim_height;
      pts.push_back(Vec3(w, c, 0.0));     // the rim circle
      pts.push_back(Vec3(0.0, -r, 0.0));  // on the mid-surface
      pts.push_back(Vec3(0.0, c, 0.0));   // axis at rim height
      pts.push_back(Vec3(0.0, 0.0, r));
      break;
    }
    case ShapeKind::sphere: pts.push_back(Vec3(r, 0.0, 0.0)); break;
  }
  return pts;
}

TEST(MpmSdf, DegeneratePointsGiveFiniteValuesAndAUnitNormal) {
  for (const Case& c : cases()) {
    for (const Vec3& p : degenerate_points(c.shape)) {
      const SdfEval e = evaluate_sdf(c.shape, p);
      EXPECT_TRUE(std::isfinite(e.distance)) << c.name << " at (" << p.transpose() << ")";
      EXPECT_TRUE(e.normal.allFinite()) << c.name << " at (" << p.transpose() << ")";
      EXPECT_TRUE(e.hessian.allFinite()) << c.name << " at (" << p.transpose() << ")";
      EXPECT_NEAR(e.normal.norm(), 1.0, 1e-15) << c.name << " at (" << p.transpose() << ")";
      EXPECT_TRUE(e.hessian == e.hessian.transpose()) << c.name << " at (" << p.transpose() << ")";
    }
  }
  // the documented choices at the centre of a sphere and of a hemisphere bowl: +y, H = 0
  EXPECT_EQ(evaluate_sdf(sphere(0.5), Vec3::Zero()).normal, Vec3(0.0, 1.0, 0.0));
  EXPECT_EQ(evaluate_sdf(bowl(0.5, 0.1, 0.0), Vec3::Zero()).normal, Vec3(0.0, 1.0, 0.0));
  EXPECT_EQ(evaluate_sdf(sphere(0.5), Vec3::Zero()).hessian, Mat3(Mat3::Zero()));
  // on a box corner: inside branch, the first face (x) of the corner's octant
  EXPECT_EQ(evaluate_sdf(box(1.0, 2.0, 3.0), Vec3(-1.0, 2.0, 3.0)).normal, Vec3(-1.0, 0.0, 0.0));
}

TEST(MpmSdf, CheapPathReturnsTheSameBits) {
  Rng rng(5);
  for (const Case& c : cases()) {
    const Sampling surface = surface_of(c.shape);
    std::vector<Vec3> pts = random_points(rng, surface, c.extent, 2000);
    for (const Vec3& p : degenerate_points(c.shape)) pts.push_back(p);
    for (const Vec3& p : pts)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(sdf_distance(c.shape, p)),
                std::bit_cast<std::uint64_t>(evaluate_sdf(c.shape, p).distance))
          << c.name << " at (" << p.transpose() << ")";
  }
}

void expect_config_error(const Shape& s, const std::string& field) {
  testing::expect_config_error_naming(s, "field '" + field + "'");
}

TEST(MpmSdf, ValidateNamesTheBadField) {
  for (const Case& c : cases()) EXPECT_NO_THROW(c.shape.validate()) << c.name;
  EXPECT_NO_THROW(capsule(0.1, 0.0).validate());
  expect_config_error(sphere(-1.0), "radius");
  expect_config_error(sphere(std::numeric_limits<double>::quiet_NaN()), "radius");
  expect_config_error(capsule(0.0, 1.0), "radius");
  expect_config_error(capsule(0.1, -0.5), "half_height");
  expect_config_error(cylinder(0.1, 0.0), "half_height");
  expect_config_error(cylinder(std::numeric_limits<double>::infinity(), 1.0), "radius");
  expect_config_error(torus(0.0, 0.1), "major_radius");
  expect_config_error(torus(0.5, 0.0), "radius");
  expect_config_error(torus(0.5, 0.6), "radius");
  expect_config_error(box(1.0, 0.0, 1.0), "half_extents.y");
  expect_config_error(box(1.0, 1.0, -2.0), "half_extents.z");
  expect_config_error(bowl(0.0, 0.1, 0.0), "radius");
  expect_config_error(bowl(1.0, 0.1, 1.0), "rim_height");
  expect_config_error(bowl(1.0, 0.1, -1.5), "rim_height");
  expect_config_error(bowl(1.0, 0.0, 0.0), "thickness");
  EXPECT_NO_THROW(bowl(1.0, 1.6, 0.6).validate());  // t = 2 w, w = 0.8
  expect_config_error(bowl(1.0, 1.7, 0.6), "thickness");
  try {
    sphere(-1.0).validate();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "shape config: field 'radius' must be finite and > 0 for a sphere, got -1");
  }
}

}  // namespace
}  // namespace dsb::mpm
