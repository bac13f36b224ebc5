#pragma once
// An MPM episode: env steps of `substeps` substeps each under per-step actions, a loss that a
// task accumulates after env steps, and the reverse pass.
//
// Reverse pass with checkpoints at env-step boundaries (design.md "MPM engine"): the forward
// pass keeps only the particles and poses before each env step (memory O(particles x env
// steps)); the reverse pass walks the env steps backwards, recomputes each one from its
// checkpoint while recording its substeps' tapes (one env step's worth: O(particles x
// substeps)), and runs the substeps' adjoints. `ReverseMode::full_history` records every
// substep's tape in the forward pass instead (memory O(particles x all substeps)); it exists to
// show, in tests, that the checkpointed adjoint is the same computation.
#include <span>
#include <vector>

#include "common/thread_team.hpp"
#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/mpm_workspace.hpp"

namespace dsb::mpm {

// The task's loss as a function of the states at env-step boundaries.
class EpisodeObjective {
 public:
  virtual ~EpisodeObjective() = default;
  // the loss term of the state after env step `step` (0-based); 0 for steps without one
  virtual double step_loss(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                           ThreadTeam& team) const = 0;
  // adds d(step_loss)/d(state) to adj and pose_adj
  virtual void step_loss_adjoint(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                                 std::vector<ParticleAdjoint>& adj, std::vector<PoseAdjoint>& pose_adj,
                                 ThreadTeam& team) const = 0;
};

enum class ReverseMode { checkpointed, full_history };

// Runs `env_steps` env steps from the model's initial state; actions has env_steps x
// model.action_dim() values (step-major). Returns the summed loss, NaN when the simulation blew
// up (a non-finite position or velocity at an env-step boundary ends the episode there).
double run_episode(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, std::span<const double> actions,
                   int env_steps, const EpisodeObjective& objective);

// The same loss and its gradient: actions_bar (same shape as actions) = dL/dactions; on return
// ws.adj holds dL/d(initial particle state) and ws.pose_adj dL/d(initial poses). NaN everywhere
// when the simulation blew up.
double run_episode_with_grad(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team,
                             std::span<const double> actions, int env_steps, const EpisodeObjective& objective,
                             std::span<double> actions_bar, ReverseMode mode = ReverseMode::checkpointed);

// true when every particle's position and velocity is finite
bool state_is_finite(const std::vector<Particle>& particles, ThreadTeam& team);

}  // namespace dsb::mpm
