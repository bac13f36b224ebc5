#include "envs/mpm/fluid_model.hpp"

#include <cmath>

#include "common/det_math.hpp"
#include "common/rng.hpp"

namespace dsb::mpm {

namespace {

// sqrt(a^2 + b^2) (std::hypot is libm's)
double planar_norm(double a, double b) { return std::sqrt(a * a + b * b); }

bool inside_box(const Vec3& x, const Vec3& lo, const Vec3& hi) {
  return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
}

}  // namespace

MpmModel build_fluid_model(const FluidConfig& cfg) {
  cfg.validate();
  MpmModel m;
  m.config = cfg.mpm;
  const double dx = cfg.mpm.dx;
  const double floor = cfg.floor_y();
  const double wall_hi_x = (cfg.mpm.grid[0] - cfg.mpm.bound) * dx;
  const double wall_hi_z = (cfg.mpm.grid[2] - cfg.mpm.bound) * dx;
  m.materials = {cfg.cube, cfg.syrup};

  // cube: a regular lattice, n per cell and axis, resting on the floor
  const int per_axis = static_cast<int>(std::lround(cfg.cube_size / dx)) * cfg.cube_particles_per_axis_per_cell;
  const double spacing = cfg.cube_size / per_axis;
  const Vec3 cube_lo(cfg.cube_xz[0] - cfg.cube_size / 2, floor, cfg.cube_xz[1] - cfg.cube_size / 2);
  const Vec3 cube_hi = cube_lo + Vec3::Constant(cfg.cube_size);
  for (int i = 0; i < per_axis; ++i)
    for (int j = 0; j < per_axis; ++j)
      for (int k = 0; k < per_axis; ++k) {
        Particle p;
        p.x = cube_lo + spacing * Vec3(i + 0.5, j + 0.5, k + 0.5);
        m.initial.push_back(p);
      }
  const int n_cube = static_cast<int>(m.initial.size());
  m.bodies.push_back({"cube", 0, 0, n_cube, spacing * spacing * spacing});

  // syrup: uniform random points in the tank up to syrup_depth, outside the cube
  const Vec3 syrup_lo(floor, floor, floor), syrup_hi(wall_hi_x, floor + cfg.syrup_depth, wall_hi_z);
  const Vec3 extent = syrup_hi - syrup_lo;
  const double volume = extent.prod();
  const auto samples = static_cast<int>(std::lround(cfg.syrup_particles_per_cell * volume / (dx * dx * dx)));
  Rng rng(cfg.seed);
  for (int s = 0; s < samples; ++s) {
    Particle p;
    p.x = syrup_lo + Vec3(rng.uniform() * extent.x(), rng.uniform() * extent.y(), rng.uniform() * extent.z());
    if (inside_box(p.x, cube_lo, cube_hi)) continue;
    m.initial.push_back(p);
  }
  const double syrup_volume_per_particle = dx * dx * dx / cfg.syrup_particles_per_cell;
  m.bodies.push_back({"syrup", 1, n_cube, static_cast<int>(m.initial.size()), syrup_volume_per_particle});

  // ladle: bowl tilted about z, handle rising from the bowl's highest rim point
  double s, c;
  dm::sincos(0.5 * cfg.bowl_tilt, &s, &c);
  const Vec3 start(cfg.ladle_start[0], cfg.ladle_start[1], cfg.ladle_start[2]);
  const Vec3 lower(cfg.ladle_lower[0], cfg.ladle_lower[1], cfg.ladle_lower[2]);
  const Vec3 upper(cfg.ladle_upper[0], cfg.ladle_upper[1], cfg.ladle_upper[2]);
  const double step_displacement = cfg.max_speed * cfg.mpm.dt * cfg.mpm.substeps;  // at action 1
  PrimitiveSpec bowl;
  bowl.name = "bowl";
  bowl.shape.kind = ShapeKind::bowl;
  bowl.shape.radius = cfg.bowl_radius;
  bowl.shape.thickness = cfg.bowl_thickness;
  bowl.shape.rim_height = cfg.bowl_rim_height;
  bowl.position = start;
  bowl.rotation = {c, 0.0, 0.0, s};
  bowl.friction = cfg.friction;
  bowl.softness = cfg.softness;
  bowl.motion = PrimitiveMotion::translate;
  bowl.action_axes = {0, 1};
  bowl.action_scale = {step_displacement, step_displacement};
  bowl.lower_bound = lower;
  bowl.upper_bound = upper;
  // the rim's highest point: the bowl's local (-1, 0, 0) direction at rim height, rotated
  const Mat3 R = Eigen::Quaterniond(c, 0.0, 0.0, s).toRotationMatrix();
  const double rim_r = std::sqrt(cfg.bowl_radius * cfg.bowl_radius - cfg.bowl_rim_height * cfg.bowl_rim_height);
  Vec3 rim_top = R * Vec3(-rim_r, cfg.bowl_rim_height, 0.0);
  if (rim_top.y() < (R * Vec3(rim_r, cfg.bowl_rim_height, 0.0)).y())
    rim_top = R * Vec3(rim_r, cfg.bowl_rim_height, 0.0);
  const Vec3 handle_offset = rim_top + Vec3(0.0, cfg.handle_half_length, 0.0);
  PrimitiveSpec handle = bowl;
  handle.name = "handle";
  handle.shape = Shape{};
  handle.shape.kind = ShapeKind::capsule;
  handle.shape.radius = cfg.handle_radius;
  handle.shape.half_height = cfg.handle_half_length;
  handle.rotation = {1.0, 0.0, 0.0, 0.0};
  handle.position = start + handle_offset;
  handle.lower_bound = lower + handle_offset;
  handle.upper_bound = upper + handle_offset;
  m.primitives = {bowl, handle};
  m.finalize("fluid");
  return m;
}

Vec3 cube_centre(const MpmModel& model, const std::vector<Particle>& particles) {
  const Body& cube = model.bodies[0];
  Vec3 sum = Vec3::Zero();
  for (int p = cube.begin; p < cube.end; ++p) sum += particles[p].x;
  return sum / static_cast<double>(cube.end - cube.begin);
}

double FluidObjective::final_loss(const std::vector<Particle>& particles, const std::vector<Pose>& poses) const {
  const Vec3 cube = cube_centre(model_, particles);
  const Vec3& bowl = poses[0].p;
  const double height = cube.y() - cfg_.floor_y();
  const double to_ladle = planar_norm(cube.x() - bowl.x(), cube.z() - bowl.z());
  const double to_axis = planar_norm(cube.x() - cfg_.tank_axis_xz[0], cube.z() - cfg_.tank_axis_xz[1]);
  return std::max(0.0, cfg_.rim_height - height) + cfg_.ladle_weight * to_ladle + cfg_.axis_weight * to_axis;
}

double FluidObjective::step_loss(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                                 ThreadTeam&) const {
  if (step != cfg_.env_steps - 1) return 0.0;
  final_cube_height_ = cube_height(particles);
  return final_loss(particles, poses);
}

double FluidObjective::cube_height(const std::vector<Particle>& particles) const {
  return cube_centre(model_, particles).y() - cfg_.floor_y();
}

void FluidObjective::step_loss_adjoint(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                                       std::vector<ParticleAdjoint>& adj, std::vector<PoseAdjoint>& pose_adj,
                                       ThreadTeam&) const {
  if (step != cfg_.env_steps - 1) return;
  const Vec3 cube = cube_centre(model_, particles);
  const Vec3& bowl = poses[0].p;
  Vec3 cube_bar = Vec3::Zero();
  // max(0, rim - height)
  if (cfg_.rim_height - (cube.y() - cfg_.floor_y()) > 0.0) cube_bar.y() -= 1.0;
  // w |xz_cube - xz_other| (gradient 0 where the distance is 0)
  auto pull = [&](double ox, double oz, double weight, Vec3* other_bar) {
    const double dxv = cube.x() - ox, dzv = cube.z() - oz;
    const double d = planar_norm(dxv, dzv);
    if (!(d > 0.0)) return;
    const Vec3 g(weight * dxv / d, 0.0, weight * dzv / d);
    cube_bar += g;
    if (other_bar) *other_bar -= g;
  };
  pull(bowl.x(), bowl.z(), cfg_.ladle_weight, &pose_adj[0].p);
  pull(cfg_.tank_axis_xz[0], cfg_.tank_axis_xz[1], cfg_.axis_weight, nullptr);
  const Body& b = model_.bodies[0];
  const Vec3 per_particle = cube_bar / static_cast<double>(b.end - b.begin);
  for (int p = b.begin; p < b.end; ++p) adj[p].x += per_particle;
}

}  // namespace dsb::mpm
