#pragma once
// What the cloth tasks (swing_env, flip_env) build alike from their configs: a flat grid of
// cols x rows vertices with the config's mass and spring damping, and a world with a floor. Each
// config (SwingConfig, FlipConfig) has the fields read here under the same names.
#include "envs/cloth/cloth_model.hpp"

namespace dsb::cloth {

// A flat grid in the x-z plane: `width` along x from `origin`, `height` along z; the config's
// cols, rows, total mass and damping per spring kind; the stiffnesses stay GridSpec's (a task
// that uses the grid's own stiffness sets them).
template <class TaskConfig>
GridSpec flat_grid_spec(const TaskConfig& cfg, double width, double height, const Vec3& origin) {
  GridSpec g;
  g.cols = cfg.cols;
  g.rows = cfg.rows;
  g.width = width;
  g.height = height;
  g.origin = origin;
  g.axis_u = Vec3::UnitX();
  g.axis_v = Vec3::UnitZ();
  g.total_mass = cfg.total_mass;
  g.structural_damping = cfg.structural_damping;
  g.shear_damping = cfg.shear_damping;
  g.bending_damping = cfg.bending_damping;
  return g;
}

// The config's world on a built grid: the floor plane y = floor_height as the only surface,
// gravity along -y, the time step, velocity damping and the floor's tangential keep; then checks
// the model (ClothModel::validate), so a task sets its anchors before this.
template <class TaskConfig>
void set_floor_world(ClothModel& c, const TaskConfig& cfg) {
  c.surfaces = {PlaneSurface::floor(cfg.floor_height)};
  c.gravity = Vec3(0.0, -cfg.gravity, 0.0);
  c.dt = cfg.dt;
  c.damping = cfg.damping;
  c.tangential_keep = cfg.tangential_keep;
  c.validate();
}

}  // namespace dsb::cloth
