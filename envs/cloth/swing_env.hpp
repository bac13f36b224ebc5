#pragma once
// The six `swing-*` tasks (swing_config.hpp) as Envs on the mass-spring cloth engine:
//   swing-stiffness-{single,corner,mesh}  16 params: the log structural stiffness of each of
//       4 x 4 patches of the cloth, x in [-1, 1] -> log k in [log k_low, log k_high] affinely;
//       a spring belongs to the patch that holds its midpoint (grid coordinates, integer
//       arithmetic: patch column = min(3, 4 (c_i + c_j) / (2 (cols - 1))), rows alike), and every
//       spring of a patch (structural k, shear shear_ratio k, bending bending_ratio k) scales
//       with it. The cloth starts at rest.
//   swing-velocity-{single,corner,mesh}   3 params: the initial velocity of every vertex (the
//       throw), x in [-1, 1]^3 -> [v_low, v_high] per axis; every patch at param 0.
// Losses (the seed study's definitions for DiffTaichi's "Swing"), at the final state:
//   single  |c - c*|, c the cloth's centre of mass (the seed's "final centre of mass to goal")
//   corner  mean over the 4 corner vertices of |x_c - x_c*|
//   mesh    mean over all vertices of |x_i - x_i*| (the seed's "mean vertex distance to a target
//           mesh"; chosen here: vertex-to-same-vertex distance, no correspondence search)
// Targets (*): the final state of the env's own rollout at its documented reference params
// (SwingConfig::stiffness_reference, velocity_reference), simulated when the model is built, so
// the loss is exactly 0 there (same code path, same bits). The gradient comes from the engine's
// reverse pass (dLoss/dk per spring, dLoss/dv0 per vertex) and the chain rule to the normalized
// params; the distance's gradient at a zero distance is taken as 0.
//
// RL view (make_rl): the params are episode constants (stiffness, the initial velocity), not
// per-step controls, and the swing itself is scripted, so an RL episode is one action, the param
// vector, after which the whole episode runs (horizon 1: for PPO/SAC a bandit over the box).
// Observation (61): positions and velocities of a 3 x 3 subsample of the vertices (rows and
// columns 0, (n - 1) / 2, n - 1), the two held corners' positions, and time as a fraction of the
// episode; before the action it shows the cloth at rest (the velocity tasks' throw is the
// action), after it the final state. final_loss() equals loss() of the action, bit for bit.
#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "envs/cloth/cloth_dynamics.hpp"
#include "envs/cloth/cloth_model.hpp"
#include "envs/cloth/swing_config.hpp"
#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"

namespace dsb::cloth {

enum class SwingParams { stiffness, velocity };
enum class SwingLoss { single, corner, mesh };

// constants of one task, built from a validated config
struct SwingModel {
  ClothModel cloth;
  std::vector<Vec3> anchor_path;  // (steps + 1) x 2: the two held corners
  int steps = 0;
  std::vector<int> spring_patch;     // (n_springs) patch index row * 4 + col in [0, 16)
  std::vector<double> spring_ratio;  // (n_springs) 1, shear_ratio or bending_ratio
  double log_k_low = 0.0, log_k_high = 0.0;
  std::array<int, 4> corners{};         // vertex indices of the 4 corners
  std::vector<double> fixed_stiffness;  // per spring, the velocity tasks' (every patch at param 0)
  std::array<int, 9> observed{};        // the RL view's 3 x 3 subsample
  // targets: the final state at the reference params
  std::vector<Vec3> target;  // (n) every vertex
  Vec3 target_com = Vec3::Zero();
};

// buffers of one rollout
struct SwingWorkspace : Workspace {
  ClothTape tape;
  ClothState state;
  std::vector<Vec3> force;        // (n) scratch
  std::vector<double> stiffness;  // (n_springs)
  ClothAdjoint final_bar;
  ClothGradient grad;
};

class SwingEnv : public ConfigModelEnv<SwingConfig, SwingModel> {
 public:
  SwingEnv(std::string name, SwingParams params, SwingLoss loss, SwingConfig cfg = {});
  nlohmann::json config() const override;
  std::unique_ptr<Workspace> make_workspace() const override;
  // one action per episode: the params (see above)
  std::unique_ptr<RlEnv> make_rl() const override;
  // x itself: the one action is the params
  std::vector<double> rl_actions(std::span<const double> x) const override { return {x.begin(), x.end()}; }
  bool renderable() const override { return true; }
  std::vector<Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_cloth.cpp

  const SwingConfig& swing_config() const { return cfg_; }
  SwingParams params() const { return params_; }
  SwingLoss loss_kind() const { return loss_; }
  // the reference params (normalized) that produce the targets
  std::vector<double> reference() const;
  // per-spring stiffness (N/m) and initial state for normalized params x
  std::vector<double> stiffness(std::span<const double> x) const;
  ClothState initial_state(std::span<const double> x) const;
  ClothState final_state(std::span<const double> x) const;
  // loss of a final state (NaN when it is not finite)
  double final_loss(const ClothState& s) const;
  // per step and vertex (steps x n, row-major), 1 where the floor projected the vertex's velocity
  // (it started the step at or below the floor moving into it): tests compare these patterns to
  // stay away from contact switches
  std::vector<char> contact_pattern(std::span<const double> x) const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;

 private:
  void fill_stiffness(const SwingModel& m, std::span<const double> x, std::vector<double>& k) const;
  void fill_initial_state(const SwingModel& m, std::span<const double> x, ClothState& s) const;

  SwingParams params_;
  SwingLoss loss_;
};

// family entry for the registry: swing-{stiffness,velocity}-{single,corner,mesh}
EnvFamily swing_family();

}  // namespace dsb::cloth
