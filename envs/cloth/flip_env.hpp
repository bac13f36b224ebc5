#pragma once
// The `flip` task (flip_config.hpp) as an Env on the mass-spring cloth engine:
//   params (15): waypoint k = 1..5 of the pan's pose (x, y, tilt) is
//       (x[3(k-1)], x[3(k-1)+1], x[3(k-1)+2]) * half_range (per DOF), reached at time
//       k segment_time; waypoint 0 is the start pose (0, 0, 0). The pose at step t is linearly
//       interpolated between the waypoints of its segment (position and tilt, so the pan's
//       velocity and angular velocity are constant within a segment); after the last segment it
//       holds waypoint 5 for the settle time.
//   loss: mean over the 4 corner vertices c of |x_c - x_c*| at the final state, where the target
//       x_c* is the corner's start position mirrored through the pan's axis (local
//       (l_x, l_y, l_z) -> (-l_x, 0, l_z): the pancake turned over about the z axis, lying on the
//       bottom) and posed by the final pan pose (waypoint 5): "flipped over, in the pan, wherever
//       the pan ended". A mirror image cannot be reached by moving the sheet in its plane (it
//       reverses the mesh's orientation), so a small loss means the pancake turned over
//       (FlipEnv::orientation checks that separately). At the start (and with the pan still, all
//       params 0) every corner is a side length, 0.14 m, from its target.
//   gradient: the engine's reverse pass gives dLoss/d(pan pose path) through the pan's normal and
//       velocity at every contact (PanSurface::sample_adjoint); the chain rule through the
//       interpolation, plus the targets' dependence on waypoint 5, gives dLoss/dx.
// RL view (make_rl): one action every control_steps steps (FlipConfig); the action a in [-1, 1]^3
//   moves the pan's pose by a * max_step over the interval (max_step = 2 half_range control_steps
//   / segment_steps per DOF, the fastest motion a waypoint param can ask for), linearly within the
//   interval; no clamp to the waypoint box (an agent may wander beyond it). Observation (61): the
//   positions and velocities of a 3 x 3 subsample of the vertices (corners, edge midpoints,
//   centre: 54), the pan pose and its velocity over the last interval (6), the elapsed fraction of
//   the episode (1). Every param vector has an action sequence (rl_actions) whose episode is the
//   same up to rounding: the pose path is the same chord by chord, computed in another order
//   (test_flip compares the losses: 1e-15 to 6e-12 m apart).
#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "envs/cloth/cloth_dynamics.hpp"
#include "envs/cloth/cloth_model.hpp"
#include "envs/cloth/flip_config.hpp"
#include "envs/cloth/pan_surface.hpp"
#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"

namespace dsb::cloth {

// constants of the task, built from a validated config
struct FlipModel {
  // the pancake with the floor as its only surface: workspaces add their own pan in front
  ClothModel cloth;
  std::vector<double> stiffness;  // (n_springs) the springs' own
  int steps = 0, segment_steps = 0;
  std::array<int, 4> corners{};               // vertex indices
  std::array<Vec3, 4> corner_target_local{};  // mirrored start positions, pan frame
  std::array<int, 9> observed{};              // the RL view's 3 x 3 subsample
};

// buffers of one rollout, with the workspace's own pan (its path is per episode)
struct FlipWorkspace : Workspace {
  ClothModel cloth;  // the model's, with surfaces {pan, floor}
  std::shared_ptr<PanSurface> pan;
  std::vector<PanPose> path;  // (steps + 1)
  ClothTape tape;
  ClothState state;
  std::vector<Vec3> force;
  ClothAdjoint final_bar;
  ClothGradient grad;
};

class FlipEnv : public ConfigModelEnv<FlipConfig, FlipModel> {
 public:
  explicit FlipEnv(std::string name, FlipConfig cfg = {});
  nlohmann::json config() const override;
  std::unique_ptr<Workspace> make_workspace() const override;
  std::unique_ptr<RlEnv> make_rl() const override;
  bool renderable() const override { return true; }
  std::vector<Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_cloth.cpp

  const FlipConfig& flip_config() const { return cfg_; }
  // waypoints 0..5 for params x
  std::array<PanPose, 6> waypoints(std::span<const double> x) const;
  // the pose at every time 0..steps
  std::vector<PanPose> pose_path(std::span<const double> x) const;
  // the final state of the episode at x
  ClothState final_state(std::span<const double> x) const;
  // loss of a final state with the pan's final pose (NaN when the state is not finite)
  double final_loss(const ClothState& s, const PanPose& final_pose) const;
  // the world targets of the 4 corners for a final pan pose
  std::array<Vec3, 4> corner_targets(const PanPose& final_pose) const;
  // the unit normal (x_{row end} - x_0) x (x_{col end} - x_0) of the corners dotted with the pan's
  // axis at pose `pan`: +1 for the pancake as it starts (flat, face up), -1 flat and turned over
  double orientation(const ClothState& s, const PanPose& pan) const;
  // per step and vertex (steps x n, row-major), the tape's contact flags: bit 0 where the pan
  // projected the vertex's velocity, bit 1 the floor (tests compare these patterns to stay away
  // from contact switches)
  std::vector<char> contact_pattern(std::span<const double> x) const;
  // the RL actions (horizon x 3, row-major) that replay params x: the same pose path, computed
  // chord by chord in another order, so the replay's loss is loss(x)'s to rounding (test_flip
  // measures 1e-15 to 6e-12 m; the contract allows 1e-9 relative)
  std::vector<double> rl_actions(std::span<const double> x) const override;
  double rl_replay_tolerance() const override { return 1e-9; }
  // the pose change per RL interval at action 1, per DOF
  std::array<double, 3> max_step() const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;

 private:
  void fill_path(std::span<const double> x, std::vector<PanPose>& path) const;
  // a fresh FlipWorkspace after a forward rollout at x with its tape kept (frames, contact_pattern)
  std::unique_ptr<Workspace> taped_rollout(std::span<const double> x) const;
};

// the model's cloth with a new pan in front of its surfaces (the workspace's and RL view's)
ClothModel cloth_with_pan(const FlipModel& m, const std::shared_ptr<PanSurface>& pan);

// family entry for the registry: `flip`
EnvFamily flip_family();

}  // namespace dsb::cloth
