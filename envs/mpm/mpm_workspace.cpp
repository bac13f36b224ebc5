#include "envs/mpm/mpm_workspace.hpp"

#include "common/error.hpp"

namespace dsb::mpm {

MpmWorkspace::MpmWorkspace(const MpmModel& model) {
  if (model.primitives.size() > static_cast<std::size_t>(kMaxPrimitives))
    throw ConfigError("mpm", "primitives", "at most " + std::to_string(kMaxPrimitives) + " primitives");
  const int n = model.particles();
  particles.resize(n);
  affine.resize(n);
  grid.resize(model.layout.nodes());
  bins.home.resize(n);
  poses = model.initial_poses;
  next_poses = poses;
  frames.resize(poses.size());
}

void MpmWorkspace::reset_state(const MpmModel& model) {
  particles = model.initial;
  poses = model.initial_poses;
}

namespace {

void size_tape(const MpmModel& model, SubstepTape& t) {
  const int n = model.particles();
  t.before.resize(n);
  t.svd.resize(n);
  t.poses.resize(model.primitives.size());
  t.bins.home.resize(n);
}

}  // namespace

SubstepTape* MpmWorkspace::forward_tapes(const MpmModel& model, int k) {
  if (static_cast<int>(step_tapes.size()) <= k) step_tapes.resize(static_cast<std::size_t>(k) + 1);
  auto& step = step_tapes[static_cast<std::size_t>(k)];
  if (step.empty()) {
    step.resize(static_cast<std::size_t>(model.config.substeps));
    for (auto& t : step) size_tape(model, t);
  }
  return step.data();
}

void MpmWorkspace::reserve_reverse(const MpmModel& model, int env_steps) {
  const int n = model.particles();
  if (static_cast<int>(checkpoints.size()) < env_steps) checkpoints.resize(env_steps);
  for (auto& c : checkpoints) {
    c.particles.resize(n);
    c.poses.resize(model.primitives.size());
  }
  const int substeps = model.config.substeps;
  if (static_cast<int>(tapes.size()) < substeps) tapes.resize(substeps);
  for (auto& t : tapes) size_tape(model, t);
  adj.resize(n);
  adj_prev.resize(n);
  advection.resize(n);
  pose_adj.resize(model.primitives.size());
  if (grid_adj.v.size() != static_cast<std::size_t>(model.layout.nodes())) grid_adj.resize(model.layout.nodes());
}

}  // namespace dsb::mpm
