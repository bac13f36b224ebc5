#pragma once
// `cartpole1` and `cartpole3`: open-loop control of a velocity-controlled cart with a chain of
// 1 or 3 links. Params per step: cart speed then one torque per joint, step-major, each in
// [-1, 1] (x 5 m/s, x 30 N m). Loss: L2 of the final tip to the target. The gradient comes from a
// reverse pass through every step (cartpole_step_adjoint), never from finite differences.
#include <memory>
#include <span>
#include <string>

#include "envs/core/env.hpp"
#include "envs/core/registry.hpp"
#include "envs/rigid/cartpole_config.hpp"
#include "envs/rigid/cartpole_dynamics.hpp"

namespace dsb {

// physical controls of one step: cart speed u (m/s) and joint torques tau (N m, links entries)
struct CartpoleControls {
  double u = 0.0;
  double tau[kMaxLinks] = {};
};

class CartpoleEnv : public Env {
 public:
  CartpoleEnv(std::string name, CartpoleConfig cfg);
  const std::string& name() const override { return name_; }
  int dim() const override { return cfg_.steps * (1 + cfg_.links); }
  bool differentiable() const override { return true; }
  double loss(std::span<const double> x) const override;
  double loss_and_grad(std::span<const double> x, std::span<double> grad) const override;
  nlohmann::json config() const override { return cfg_.to_json(); }
  std::unique_ptr<RlEnv> make_rl() const override;

  const CartpoleConfig& cartpole_config() const { return cfg_; }
  const CartpoleModel& model() const { return model_; }
  // the parameter map: physical controls of step t for the normalized parameters x (the
  // references drive their engines with it)
  CartpoleControls controls(std::span<const double> x, int t) const;
  // the trajectory of states (steps + 1) for the parameters x: used by tests and references
  std::vector<CartpoleState> trajectory(std::span<const double> x) const;
  // loss of a final state (NaN when it is not finite)
  double final_loss(const CartpoleState& s) const;

 private:
  std::string name_;
  CartpoleConfig cfg_;
  CartpoleModel model_;
};

// family entry for the registry: links = 1 gives `cartpole1`, 3 gives `cartpole3`
EnvFamily cartpole_family(int links);

}  // namespace dsb
