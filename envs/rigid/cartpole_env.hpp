#pragma once
// `cartpole1` and `cartpole3`: open-loop control of a velocity-controlled cart with a chain of
// 1 or 3 links. Params per step: cart speed then one torque per joint, step-major, each in
// [-1, 1] (x 5 m/s, x 30 N m). Loss: L2 of the final tip to the target. The gradient comes from a
// reverse pass through every step (cartpole_step_adjoint), never from finite differences.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"
#include "envs/rigid/cartpole_config.hpp"
#include "envs/rigid/cartpole_dynamics.hpp"

namespace dsb {

// buffers of one rollout: the states before every step and what each step's reverse needs
struct CartpoleWorkspace : Workspace {
  std::vector<CartpoleState> states;      // steps + 1
  std::vector<CartpoleStepCache> caches;  // steps
};

// physical controls of one step: cart speed u (m/s) and joint torques tau (N m, links entries)
struct CartpoleControls {
  double u = 0.0;
  double tau[kMaxLinks] = {};
};

class CartpoleEnv : public ConfigModelEnv<CartpoleConfig, CartpoleModel> {
 public:
  CartpoleEnv(std::string name, CartpoleConfig cfg);
  std::unique_ptr<Workspace> make_workspace() const override;
  std::unique_ptr<RlEnv> make_rl() const override;
  // x itself: the params are every step's normalized controls, as the RL view's actions are
  std::vector<double> rl_actions(std::span<const double> x) const override { return {x.begin(), x.end()}; }
  bool renderable() const override { return true; }
  std::vector<Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_rigid.cpp

  const CartpoleConfig& cartpole_config() const { return cfg_; }
  // the parameter map: physical controls of step t for the normalized parameters x (the
  // references drive their engines with it)
  CartpoleControls controls(std::span<const double> x, int t) const;
  // the trajectory of states (steps + 1) for the parameters x: used by tests and references
  std::vector<CartpoleState> trajectory(std::span<const double> x) const;
  // loss of a final state (NaN when it is not finite)
  double final_loss(const CartpoleState& s) const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;
};

// family entry for the registry: links = 1 gives `cartpole1`, 3 gives `cartpole3`
EnvFamily cartpole_family(int links);

}  // namespace dsb
