#include "envs/mpm/plb_model.hpp"

#include <cmath>

#include "common/det_math.hpp"
#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/core/data_dir.hpp"

namespace dsb::mpm {

namespace {

// PlasticineLab's shape maker: a box uniformly in [-size/2, size/2] + centre; a sphere as a
// Gaussian direction x U^(1/3) x radius
Vec3 sample(const PlbShape& s, Rng& rng) {
  if (s.kind == PlbShape::Kind::box) {
    const double u = rng.uniform(), v = rng.uniform(), w = rng.uniform();
    return s.centre + Vec3((u - 0.5) * s.size.x(), (v - 0.5) * s.size.y(), (w - 0.5) * s.size.z());
  }
  Vec3 d;
  do {
    const double a = rng.normal(), b = rng.normal(), c = rng.normal();
    d = Vec3(a, b, c);
  } while (!(d.squaredNorm() > 0.0));
  return s.centre + d.normalized() * (dm::cbrt(rng.uniform()) * s.radius);
}

}  // namespace

MpmModel build_plb_mpm_model(const PlbConfig& cfg) {
  cfg.validate();
  const PlbTask& task = *find_plb_task(cfg.task);
  MpmModel m;
  m.config = cfg.mpm;
  Material mat;
  mat.kind = MaterialKind::plastic;
  mat.youngs_modulus = task.youngs_modulus;
  mat.poisson_ratio = task.poisson_ratio;
  mat.yield_stress = task.yield_stress;
  mat.density = cfg.density;
  m.materials = {mat};
  Rng rng(cfg.seed);
  for (const auto& shape : task.shapes)
    for (int i = 0; i < shape.particles; ++i) {
      Particle p;
      p.x = sample(shape, rng);
      // PlasticineLab's shapes touch y = 0; keep every particle inside the clamp
      for (int a = 0; a < 3; ++a) p.x[a] = std::min(std::max(p.x[a], m.config.clamp_low()), m.config.clamp_high(a));
      m.initial.push_back(p);
    }
  m.bodies.push_back({"plasticine", 0, 0, m.particles(), cfg.particle_volume});
  m.primitives = task.primitives;
  for (auto& p : m.primitives) p.softness = cfg.softness;
  m.finalize("plb-" + cfg.task);
  return m;
}

std::string plb_target_path(const std::string& task) { return data_dir() + "/targets/plb-" + task + ".txt.gz"; }

PlbModel build_plb_model(const PlbConfig& cfg) {
  PlbModel model;
  model.mpm = build_plb_mpm_model(cfg);
  model.target = cfg.target_file ? cfg.target_file->grid : read_grid_gz(plb_target_path(cfg.task));
  const auto& n = model.mpm.layout.n;
  if (model.target.n != n)
    throw UsageError("target " + (cfg.target_file ? std::string("file") : plb_target_path(cfg.task)) + " has " +
                     std::to_string(model.target.n[0]) + " nodes per axis, the model's grid " + std::to_string(n[0]));
  model.target_sdf = distance_to_mass(model.target, cfg.target_threshold, cfg.mpm.dx);
  for (double v : model.target.values) {
    model.target_sum += v;
    model.target_abs_sum += std::abs(v);
    model.target_max = std::max(model.target_max, v);
  }
  for (std::size_t i = 0; i < model.mpm.primitives.size(); ++i)
    if (model.mpm.primitives[i].action_dim() > 0) model.movable.push_back(static_cast<int>(i));
  return model;
}

}  // namespace dsb::mpm
