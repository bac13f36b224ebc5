#pragma once
// Test helper: small MPM scenes built directly on the engine (no task), and a smooth objective
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

inline mpm::Material elastic(double E, double nu, double density = 1.0) {
  mpm::Material mat;
  mat.kind = mpm::MaterialKind::elastic;
  mat.youngs_modulus = E;
  mat.poisson_ratio = nu;
  mat.density = density;
  return mat;
}

inline mpm::Material plastic(double E, double nu, double yield, double density = 1.0) {
  mpm::Material mat = elastic(E, nu, density);
  mat.kind = mpm::MaterialKind::plastic;
  mat.yield_stress = yield;
  return mat;
}

inline mpm::Material fluid(double K, double eta, double density = 1.0) {
  mpm::Material mat;
  mat.kind = mpm::MaterialKind::fluid;
  mat.bulk_modulus = K;
  mat.viscosity = eta;
  mat.density = density;
  return mat;
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
