#pragma once
// The environment contract: a parameter vector x in the normalized box [-1, 1]^dim maps to a
// scalar loss. Each env owns the affine map from that box to physical units. Differentiable envs
// also return dLoss/dx in normalized units. RL-capable envs expose a per-step interface with the
// same dynamics. Envs are immutable after construction; loss() is const and thread-safe.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace dsb {

// Per-step interface for RL (reset / observe / step) over the same dynamics as loss().
class RlEnv {
 public:
  virtual ~RlEnv() = default;
  virtual int observation_dim() const = 0;
  virtual int action_dim() const = 0;   // actions live in [-1, 1]^action_dim
  virtual int horizon() const = 0;      // steps per episode
  virtual void reset() = 0;
  virtual std::vector<double> observe() const = 0;
  virtual void step(std::span<const double> action) = 0;
  virtual bool done() const = 0;
  // the episode loss once done() (the same number loss() gives for the same actions)
  virtual double final_loss() const = 0;
};

class Env {
 public:
  virtual ~Env() = default;
  virtual const std::string& name() const = 0;
  virtual int dim() const = 0;
  virtual bool differentiable() const = 0;
  // Loss at x (size dim, inside [-1, 1]); NaN when the simulation blew up.
  virtual double loss(std::span<const double> x) const = 0;
  // Loss and dLoss/dx (normalized units) at x; grad has size dim. Throws std::logic_error on an
  // env that is not differentiable. NaN loss and gradient when the simulation blew up.
  virtual double loss_and_grad(std::span<const double> x, std::span<double> grad) const;
  // The resolved configuration (every constant that changes the loss), stored with each run.
  virtual nlohmann::json config() const = 0;
  // nullptr when the env has no per-step interface
  virtual std::unique_ptr<RlEnv> make_rl() const { return nullptr; }
  bool supports_rl() const { return make_rl() != nullptr; }
};

}  // namespace dsb
