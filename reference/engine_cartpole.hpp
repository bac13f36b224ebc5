#pragma once
// What the cartpole models in MuJoCo and Bullet (MujocoCartpole, BulletCartpole) share: their
// interface, the whole rollout of an env's parameters, and our state read from the engine's
// relative joint coordinates. Each engine's model does its own reset, step and readings.
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "envs/rigid/cartpole_config.hpp"
#include "envs/rigid/cartpole_dynamics.hpp"
#include "envs/rigid/cartpole_env.hpp"

namespace dsb::reference {

class EngineCartpole {
 public:
  virtual ~EngineCartpole() = default;
  // the config's initial state
  virtual void reset() = 0;
  // one step: cart speed becomes u (m/s), joint torques tau (links entries, N m)
  virtual void step(double u, const double* tau) = 0;
  // the current state in our conventions (absolute angles)
  virtual CartpoleState state() const = 0;
  // tip of the chain (our x, y) from the engine's kinematics
  virtual Eigen::Vector2d tip() const = 0;
  // tips of the whole rollout for the normalized parameters x of `env` (steps + 1 entries), each
  // step driven by env.controls(x, t); throws std::invalid_argument when env's config is not
  // the one this model was built from
  std::vector<Eigen::Vector2d> tip_trajectory(const CartpoleEnv& env, std::span<const double> x);
  const CartpoleConfig& config() const { return cfg_; }

 protected:
  // model: the class's name, for error messages ("MujocoCartpole")
  EngineCartpole(std::string model, const CartpoleConfig& cfg) : cfg_(cfg), model_(std::move(model)) {}
  // our state from the engine's joint coordinates q, dq (links + 1 entries each: the cart's slide,
  // then each link's angle relative to the one before): absolute angles are their running sums
  CartpoleState state_from_joints(std::span<const double> q, std::span<const double> dq) const;

  CartpoleConfig cfg_;

 private:
  std::string model_;
};

}  // namespace dsb::reference
