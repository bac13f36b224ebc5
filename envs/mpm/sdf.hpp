#pragma once
// Signed distance functions of the rigid primitives of the MLS-MPM engine (grid contact in the
// style of PlasticineLab: a grid node near a primitive has its velocity projected with the SDF and
// its normal). Everything is in the shape's local frame (y up); the engine rotates the normal and
// Hessian to the world frame. The reverse pass needs the distance, its gradient (the outward unit
// normal) and the gradient's Jacobian (the Hessian of the distance), so every shape provides all
// three analytically, region by region.
//
// Determinism: only + - * / sqrt, abs, min, max (no libm transcendental functions), compiled with
// -ffp-contract=off: the same bits on every x86-64 CPU. sdf_distance() runs the same arithmetic as
// evaluate_sdf() and returns the same bits.
//
// Where the distance is not differentiable (the medial axis: the centre of a sphere, the segment
// of a capsule, the axis of a cylinder/torus/bowl, the tube circle of a torus, the mid-surface of
// a bowl wall, the diagonal planes inside a box or cylinder) the result is finite and fixed: see
// the comment of each shape in sdf.cpp. Nothing divides by zero; no NaN for finite input.
#include "envs/mpm/mpm_types.hpp"

namespace dsb::mpm {

enum class ShapeKind { sphere, capsule, cylinder, torus, box, bowl };

const char* shape_kind_name(ShapeKind kind);

// A rigid primitive, parameters in its local frame (sim units). Fields a kind does not use are
// ignored.
struct Shape {
  ShapeKind kind = ShapeKind::sphere;
  double radius = 0.0;               // sphere radius; capsule radius; cylinder radius (in xz); torus tube
                                     // (minor) radius; bowl: radius of the spherical shell's mid-surface
  double half_height = 0.0;          // capsule: half length of its segment along y (from -h to +h);
                                     // cylinder: half height along y
  double major_radius = 0.0;         // torus: radius of the tube's centre circle in xz (axis = y)
  Vec3 half_extents = Vec3::Zero();  // box
  double thickness = 0.0;            // bowl: wall thickness (the shell is mid-surface +- thickness / 2)
  double rim_height = 0.0;           // bowl: the shell is the part of the sphere below y = rim_height
                                     // (-radius < rim_height < radius; 0 = a hemisphere opening upward)

  // throws dsb::ConfigError naming the bad field:
  //   sphere: radius > 0; capsule: radius > 0, half_height >= 0; cylinder: radius, half_height > 0;
  //   torus: 0 < radius <= major_radius (a ring or horn torus: the formula is exact only there);
  //   box: half_extents > 0; bowl: radius > 0, |rim_height| < radius,
  //   0 < thickness <= 2 sqrt(radius^2 - rim_height^2) (the wall is no thicker than the opening's
  //   radius allows: the SDF is exact only there)
  void validate() const;
};

struct SdfEval {
  double distance = 0.0;        // signed distance, negative inside
  Vec3 normal = Vec3::Zero();   // gradient of the distance (unit; outward)
  Mat3 hessian = Mat3::Zero();  // d normal / d p (symmetric, hessian * normal = 0)
};

SdfEval evaluate_sdf(const Shape& shape, const Vec3& p_local);
double sdf_distance(const Shape& shape, const Vec3& p_local);  // distance only (cheap path)

}  // namespace dsb::mpm
