#pragma once
// `bounce`: a ball (point mass with a contact radius, no spin: Warp's particle) thrown from
// (0, 1, 0) bounces on the ground y = 0 and the wall x = wall_x under the penalty contact law of
// contact.hpp; semi-implicit Euler. Params (3): the initial velocity, affine from [-1, 1]^3 to
// [v_low, v_high] per component. Loss: L2 of the final centre to the target. The gradient comes
// from a reverse pass through every step (bounce_step_adjoint), contact forces included.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"
#include "envs/rigid/ball.hpp"
#include "envs/rigid/bounce_config.hpp"

namespace dsb {

using BallState = BallStateOf<3>;

// constants of one simulation, built from a validated config
struct BounceModel : BallConstants {
  double wall_x = 0.0;  // m, wall plane x = wall_x (normal -x)

  static BounceModel build(const BounceConfig& cfg);
};

// what the reverse pass needs from one step: the contact Jacobians (3 x 3) and the active contacts
struct BounceStepCache : BallForceJacobians<3> {
  bool ground = false, wall = false;  // which contacts were active
};

// one semi-implicit Euler step: v += dt (g + f(x, v) / m); x += dt v. Fills `cache` when given.
void bounce_step(const BounceModel& m, BallState& s, BounceStepCache* cache = nullptr);

// reverse of bounce_step: `adj` holds dLoss/d(state after the step) on entry and
// dLoss/d(state before it) on exit
void bounce_step_adjoint(const BounceModel& m, const BounceStepCache& cache, BallState& adj);

// steps in which each surface touched the ball (tests use it to stay away from contact events)
struct BounceContactSteps {
  int ground = 0, wall = 0;
  bool operator==(const BounceContactSteps&) const = default;
};

// buffers of one rollout: what each step's reverse needs
struct BounceWorkspace : Workspace {
  std::vector<BounceStepCache> caches;  // steps
};

class BounceEnv : public ConfigModelEnv<BounceConfig, BounceModel> {
 public:
  explicit BounceEnv(BounceConfig cfg = {});
  std::unique_ptr<Workspace> make_workspace() const override;
  bool renderable() const override { return true; }
  std::vector<Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_rigid.cpp

  const BounceConfig& bounce_config() const { return cfg_; }
  // physical initial velocity (m/s) for the normalized parameters x (size 3)
  Eigen::Vector3d initial_velocity(std::span<const double> x) const;
  BallState initial_state(std::span<const double> x) const;
  // the states of the rollout (steps + 1, the initial one first): used by tests and references
  std::vector<BallState> trajectory(std::span<const double> x) const;
  BounceContactSteps contact_steps(std::span<const double> x) const;
  // loss of a final state (NaN when it is not finite)
  double final_loss(const BallState& s) const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;
};

// family entry for the registry: `bounce`
EnvFamily bounce_family();

}  // namespace dsb
