#pragma once
// Test helper: small MPM models built directly on the engine (no task), and a smooth objective
// of the particle positions and primitive poses for gradient checks.
#include <string>
#include <vector>

#include "common/rng.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/mpm_model.hpp"

namespace dsb::testing {

using mpm::Mat3;
using mpm::Vec3;

// An empty model on an n^3 grid of spacing dx.
inline mpm::MpmModel empty_model(int n, double dx, double dt, int substeps, const Vec3& gravity) {
  mpm::MpmModel m;
  m.config.grid = {n, n, n};
  m.config.dx = dx;
  m.config.dt = dt;
  m.config.substeps = substeps;
  m.config.gravity = gravity;
  return m;
}

// Appends a body of particles on a lattice, `per_axis` per cell and axis, filling [lo, hi].
inline void add_block(mpm::MpmModel& m, const std::string& name, const mpm::Material& mat, const Vec3& lo,
                      const Vec3& hi, int per_axis) {
  m.materials.push_back(mat);
  const double h = m.config.dx / per_axis;
  const int begin = m.particles();
  for (double x = lo.x() + h / 2; x < hi.x(); x += h)
    for (double y = lo.y() + h / 2; y < hi.y(); y += h)
      for (double z = lo.z() + h / 2; z < hi.z(); z += h) {
        mpm::Particle p;
        p.x = Vec3(x, y, z);
        m.initial.push_back(p);
      }
  m.bodies.push_back({name, static_cast<int>(m.materials.size()) - 1, begin, m.particles(), h * h * h});
}

// materials by their fields (the ones not named keep Material's defaults)
inline mpm::Material elastic(double E, double nu, double density = 1.0) {
  return {.kind = mpm::MaterialKind::elastic, .youngs_modulus = E, .poisson_ratio = nu, .density = density};
}

inline mpm::Material plastic(double E, double nu, double yield, double density = 1.0) {
  mpm::Material mat = elastic(E, nu, density);
  mat.kind = mpm::MaterialKind::plastic;
  mat.yield_stress = yield;
  return mat;
}

inline mpm::Material fluid(double K, double eta, double density = 1.0) {
  return {.kind = mpm::MaterialKind::fluid, .density = density, .bulk_modulus = K, .viscosity = eta};
}

// A translating primitive with soft contact (band ln 10 / 300) and friction 0.5, moved by actions
// along x, y, z.
inline mpm::PrimitiveSpec translating_primitive(const char* name, mpm::ShapeKind kind, const Vec3& at) {
  mpm::PrimitiveSpec p;
  p.name = name;
  p.shape.kind = kind;
  p.position = at;
  p.softness = 300.0;  // contact band ln 10 / 300 = 0.25 dx
  p.friction = 0.5;
  p.motion = mpm::PrimitiveMotion::translate;
  p.action_axes = {0, 1, 2};
  p.action_scale = {0.02, 0.02, 0.02};
  return p;
}

// three bodies (plastic, elastic, fluid) on a 32^3 grid and the seven primitives, each touching
// a body: sphere, capsule, cylinder, torus, box, bowl, rolling pin
inline mpm::MpmModel every_primitive_model(int substeps) {
  auto m = empty_model(32, 1.0 / 32, 4e-4, substeps, Vec3(0.0, -5.0, 0.0));
  const double floor = 3.0 / 32;
  add_block(m, "plastic", plastic(400.0, 0.2, 4.0), Vec3(0.15, floor, 0.2), Vec3(0.35, 0.25, 0.4), 2);
  add_block(m, "elastic", elastic(300.0, 0.3), Vec3(0.45, floor, 0.2), Vec3(0.6, 0.22, 0.4), 2);
  add_block(m, "fluid", fluid(200.0, 0.05), Vec3(0.65, floor, 0.55), Vec3(0.85, 0.2, 0.8), 2);
  auto sphere = translating_primitive("sphere", mpm::ShapeKind::sphere, Vec3(0.22, 0.29, 0.3));
  sphere.shape.radius = 0.05;
  auto capsule = translating_primitive("capsule", mpm::ShapeKind::capsule, Vec3(0.5, 0.3, 0.3));
  capsule.shape.radius = 0.03;
  capsule.shape.half_height = 0.06;
  auto cylinder = translating_primitive("cylinder", mpm::ShapeKind::cylinder, Vec3(0.75, 0.22, 0.7));
  cylinder.shape.radius = 0.05;
  cylinder.shape.half_height = 0.03;
  auto torus = translating_primitive("torus", mpm::ShapeKind::torus, Vec3(0.3, 0.27, 0.25));
  torus.shape.major_radius = 0.05;
  torus.shape.radius = 0.02;
  torus.rotation = {0.9238795325112867, 0.3826834323650898, 0.0, 0.0};  // tilted 45 deg about x
  auto box = translating_primitive("box", mpm::ShapeKind::box, Vec3(0.56, 0.245, 0.33));
  box.shape.half_extents = Vec3(0.03, 0.03, 0.04);
  box.rotation = {0.9659258262890683, 0.0, 0.25881904510234, 0.0};  // 30 deg about y
  auto bowl = translating_primitive("bowl", mpm::ShapeKind::bowl, Vec3(0.72, 0.25, 0.62));
  bowl.shape.radius = 0.06;
  bowl.shape.thickness = 0.02;
  bowl.rotation = {0.9238795325112867, 0.0, 0.0, -0.3826834323650898};
  auto pin = translating_primitive("rolling_pin", mpm::ShapeKind::capsule, Vec3(0.27, 0.275, 0.33));
  pin.shape.radius = 0.03;
  pin.shape.half_height = 0.08;
  pin.rotation = {0.7071067811865476, 0.7071067811865476, 0.0, 0.0};  // axis along z
  pin.motion = mpm::PrimitiveMotion::rolling_pin;
  pin.action_axes.clear();
  pin.action_scale = {0.6, 0.2, 0.01};  // roll, yaw, vertical per env step
  m.primitives = {sphere, capsule, cylinder, torus, box, bowl, pin};
  for (auto& p : m.primitives) {
    p.lower_bound = Vec3::Zero();
    p.upper_bound = Vec3::Ones();
  }
  m.finalize("test");
  return m;
}

// L = sum over env steps and particles of (a . x_p + b |x_p - c|^2 + e . v_p) / N
//     + sum over primitives of (f . p_pose); smooth, so central differences are trustworthy.
class SmoothObjective : public mpm::EpisodeObjective {
 public:
  Vec3 a = Vec3(0.3, -0.7, 0.5), c = Vec3(0.5, 0.4, 0.5), e = Vec3(0.01, 0.02, -0.03), f = Vec3(0.2, 0.1, -0.3);
  double b = 2.0;
  double step_loss(int, const std::vector<mpm::Particle>& ps, const std::vector<mpm::Pose>& poses,
                   ThreadTeam&) const override {
    double sum = 0.0;
    for (const auto& p : ps) sum += a.dot(p.x) + b * (p.x - c).squaredNorm() + e.dot(p.v);
    double prim = 0.0;
    for (const auto& q : poses) prim += f.dot(q.p);
    return sum / static_cast<double>(ps.size()) + prim;
  }
  void step_loss_adjoint(int, const std::vector<mpm::Particle>& ps, const std::vector<mpm::Pose>&,
                         std::vector<mpm::ParticleAdjoint>& adj, std::vector<mpm::PoseAdjoint>& pose_adj,
                         ThreadTeam&) const override {
    const double inv = 1.0 / static_cast<double>(ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) {
      adj[i].x += inv * (a + 2.0 * b * (ps[i].x - c));
      adj[i].v += inv * e;
    }
    for (auto& q : pose_adj) q.p += f;
  }
};

}  // namespace dsb::testing
