#pragma once
// The environment contract: a parameter vector x in the normalized box [-1, 1]^dim maps to a
// scalar loss. Each env owns the affine map from that box to physical units. Differentiable envs
// also return dLoss/dx in normalized units. RL-capable envs expose a per-step interface with the
// same dynamics.
//
// Model and workspace (MuJoCo's mjModel / mjData split): an Env object is the immutable model,
// shared by every run and thread that uses it (harness: shared_env in registry.hpp). Constructing
// one is cheap (config and metadata only); anything expensive (particles, meshes, targets, tables)
// is built lazily on the first rollout (envs/core/lazy_model.hpp). A rollout's mutable buffers
// live in a Workspace made by make_workspace() and reused across rollouts by one thread at a time,
// so a rollout allocates nothing in its hot loop. A rollout may use the threads of a ThreadTeam;
// its loss and gradient are bit-identical for every team size (fixed reduction order,
// common/parallel.hpp).
#include <cstddef>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/thread_team.hpp"
#include "envs/core/scene.hpp"

namespace dsb {

// How the loss behaves inside a gradient check's window (h = 1e-6, normalized units): what the env
// contract (tests/test_env_contract.cpp) may demand of the analytic gradient.
enum class Smoothness {
  // differentiable at almost every point at that scale: central differences match the gradient
  // (the synthetic functions, the cartpoles, the particle envs' short-horizon variants)
  smooth,
  // contact switches that such a window often straddles (penalty contacts turning on and off, the
  // cloth's floor and pan): the gradient is the derivative of the piece x lies in and may differ
  // from the differences across a switch, so only its direction is held to them, statistically
  // (the rigid contact envs and the cloth envs; docs/gradient-quality.md measures how often)
  piecewise,
};

// What listing, grid expansion, sharding, planning and resume need to know, without a model.
struct EnvInfo {
  std::string name;
  int dim = 0;
  bool differentiable = false;
  bool rl = false;        // has a per-step interface (make_rl)
  bool threaded = false;  // a rollout uses the threads of its team
  // seconds of one gradient episode (with the default tape memory) on one core of the machine the
  // project calibrates on (a 2-core AMD EPYC), for plans before `harness calibrate` measures this one
  double cost_hint_s = 0.0;
  std::string metric;                // name of an optional second per-episode metric ("" for none)
  double cost_hint_forward_s = 0.0;  // the same of a forward episode (0: cost_hint_s)
  Smoothness smoothness = Smoothness::smooth;
};

// Per-step interface for RL (reset / observe / step) over the same dynamics as loss().
class RlEnv {
 public:
  virtual ~RlEnv() = default;
  virtual int observation_dim() const = 0;
  virtual int action_dim() const = 0;  // actions live in [-1, 1]^action_dim
  virtual int horizon() const = 0;     // steps per episode
  // env steps an RL agent's action is held for (the seed's action repeat: 5, the cartpoles 1)
  virtual int action_repeat() const { return 5; }
  virtual void reset() = 0;
  virtual std::vector<double> observe() const = 0;
  virtual void step(std::span<const double> action) = 0;
  virtual bool done() const = 0;
  // the episode loss once done() (the same number loss() gives for the same actions)
  virtual double final_loss() const = 0;
  // the env's second metric (EnvInfo::metric) once done(): the number episode_metric() gives after
  // loss() of the same actions; NaN for an env without one or an episode that blew up
  virtual double final_metric() const { return std::numeric_limits<double>::quiet_NaN(); }
};

// The mutable buffers of one rollout. Envs derive their own.
class Workspace {
 public:
  virtual ~Workspace() = default;
  // The bytes a gradient rollout may keep from its forward pass to spare its reverse pass a
  // recomputation (the MPM envs' substep tapes, envs/mpm/episode.hpp); 0: keep nothing beyond
  // what the env needs. Changes no result, only time and memory; the harness sets it per run.
  std::size_t tape_memory_bytes = 0;
};

class Env {
 public:
  explicit Env(EnvInfo info) : info_(std::move(info)) {}
  virtual ~Env() = default;
  Env(const Env&) = delete;
  Env& operator=(const Env&) = delete;

  const EnvInfo& info() const { return info_; }
  const std::string& name() const { return info_.name; }
  int dim() const { return info_.dim; }
  bool differentiable() const { return info_.differentiable; }
  bool supports_rl() const { return info_.rl; }

  // The resolved configuration (every constant that changes the loss), stored with each run.
  // Cheap: never builds the model.
  virtual nlohmann::json config() const = 0;

  // Buffers for rollouts of this env (builds the model if it is not built yet).
  virtual std::unique_ptr<Workspace> make_workspace() const { return std::make_unique<Workspace>(); }

  // Loss at x (size dim, inside [-1, 1]); NaN when the simulation blew up. `ws` must come from
  // this env's make_workspace(); `team` may be of any size (same bits).
  double loss(std::span<const double> x, Workspace& ws, ThreadTeam& team) const { return rollout(x, ws, team); }
  // Loss and dLoss/dx (normalized units) at x; grad has size dim. Throws std::logic_error on an
  // env that is not differentiable. NaN loss and gradient when the simulation blew up.
  double loss_and_grad(std::span<const double> x, std::span<double> grad, Workspace& ws, ThreadTeam& team) const {
    return rollout_with_grad(x, grad, ws, team);
  }
  // Convenience forms (tests, one-off commands): a fresh workspace, one thread.
  double loss(std::span<const double> x) const;
  double loss_and_grad(std::span<const double> x, std::span<double> grad) const;

  // The optional second metric (info().metric) of the last rollout run in `ws`, e.g. the soft IoU
  // of PlasticineLab's tasks; NaN when the env has none or the rollout failed. Stored per episode.
  virtual double episode_metric(const Workspace& ws) const;

  // nullptr when the env has no per-step interface
  virtual std::unique_ptr<RlEnv> make_rl() const { return nullptr; }
  // The RL actions whose episode is loss(x)'s: (horizon x action_dim) row by row, each in [-1, 1].
  // Stepped through a fresh make_rl() view, they end with final_loss() == loss(x), bit for bit, or
  // within rl_replay_tolerance() relative (of max(1, |loss|)) where the env says so. Empty when the
  // env has no per-step interface.
  virtual std::vector<double> rl_actions(std::span<const double> /*x*/) const { return {}; }
  virtual double rl_replay_tolerance() const { return 0.0; }

  // Pictures of the rollout at x (`harness render`): the state after each of frame_steps(steps, n)
  // with the target drawn into every frame, recorded from the env's own rollout. Envs that are not
  // simulated (synthetic functions) are not renderable and return no frames.
  virtual bool renderable() const { return false; }
  virtual std::vector<Frame> frames(std::span<const double> /*x*/, int /*n*/, ThreadTeam& /*team*/) const { return {}; }
  // A picture of the env's target on its own, without a rollout (`harness render --target`): the
  // PlasticineLab tasks draw their target grid (frames_mpm.cpp). Empty where the env has no target
  // shape to draw.
  virtual std::vector<Frame> target_frames() const { return {}; }

 protected:
  virtual double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const = 0;
  virtual double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                                   ThreadTeam& team) const;

 private:
  EnvInfo info_;
};

}  // namespace dsb
