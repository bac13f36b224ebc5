#pragma once
// An MPM episode: env steps of `substeps` substeps each under per-step actions, a loss that a
// task accumulates after env steps, and the reverse pass.
//
// Reverse pass: the forward pass keeps the state before every env step (a checkpoint: memory
// O(particles x env steps)) and, while they fit a memory budget, the tapes of every substep of
// the env steps from the first on (memory O(particles x substeps) per env step). The reverse pass
// walks the env steps backwards: a taped env step is reversed from its tapes; any other is first
// recomputed from its checkpoint while recording its substeps' tapes (one env step's worth), then
// reversed. Recomputation repeats the forward pass exactly, so the gradient is the same bits for
// any budget; a budget that holds every tape saves the whole recomputation (about a forward
// pass), one of zero keeps only checkpoints.
#include <cstddef>
#include <limits>
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

// tape_bytes that keeps every substep's tape
inline constexpr std::size_t kTapeEverything = std::numeric_limits<std::size_t>::max();

// Runs `env_steps` env steps from the model's initial state; actions has env_steps x
// model.action_dim() values (step-major). Returns the summed loss, NaN when the simulation blew
// up (a non-finite position or velocity at an env-step boundary ends the episode there).
double run_episode(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, std::span<const double> actions,
                   int env_steps, const EpisodeObjective& objective);

// The same loss and its gradient: actions_bar (same shape as actions) = dL/dactions; on return
// ws.adj holds dL/d(initial particle state) and ws.pose_adj dL/d(initial poses). NaN everywhere
// when the simulation blew up. The forward pass tapes env steps from the first on while the
// tapes (tape_bytes(), counted as they are recorded) fit `tape_bytes`: 0 tapes none,
// kTapeEverything all. ws.taped_env_steps says how many it taped.
double run_episode_with_grad(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, std::span<const double> actions,
                             int env_steps, const EpisodeObjective& objective, std::span<double> actions_bar,
                             std::size_t tape_bytes = 0);

// the bytes the buffers of one substep's tape hold (their capacities)
std::size_t tape_bytes(const SubstepTape& tape);

// true when every particle's position and velocity is finite
bool state_is_finite(const std::vector<Particle>& particles, ThreadTeam& team);

}  // namespace dsb::mpm
