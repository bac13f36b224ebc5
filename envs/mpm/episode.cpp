#include "envs/mpm/episode.hpp"

#include <algorithm>
#include <limits>

#include "common/parallel.hpp"
#include "envs/mpm/substep.hpp"

namespace dsb::mpm {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Advances one env step; records tapes[0 .. substeps) when given.
void env_step(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions, SubstepTape* tapes) {
  for (int s = 0; s < model.config.substeps; ++s) substep(model, ws, team, actions, tapes ? &tapes[s] : nullptr);
}

void zero_adjoints(MpmWorkspace& ws) {
  std::fill(ws.adj.begin(), ws.adj.end(), zero_adjoint());
  std::fill(ws.pose_adj.begin(), ws.pose_adj.end(), PoseAdjoint{});
}

}  // namespace

bool state_is_finite(const std::vector<Particle>& particles, ThreadTeam& team) {
  const double bad = parallel_sum(team, static_cast<std::int64_t>(particles.size()), kParticleGrain * 8, 0.0,
                                  [&](std::int64_t begin, std::int64_t end, double acc) {
                                    for (std::int64_t p = begin; p < end; ++p)
                                      if (!particles[p].x.allFinite() || !particles[p].v.allFinite()) acc += 1.0;
                                    return acc;
                                  });
  return bad == 0.0;
}

double run_episode(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, std::span<const double> actions,
                   int env_steps, const EpisodeObjective& objective) {
  const int adim = model.action_dim();
  ws.reset_state(model);
  if (ws.observer) ws.observer->at_step(0, ws.particles, ws.poses);
  double loss = 0.0;
  for (int k = 0; k < env_steps; ++k) {
    env_step(model, ws, team, actions.data() + static_cast<std::size_t>(k) * adim, nullptr);
    if (!state_is_finite(ws.particles, team)) return kNaN;
    loss += objective.step_loss(k, ws.particles, ws.poses, team);
    if (ws.observer) ws.observer->at_step(k + 1, ws.particles, ws.poses);
  }
  return loss;
}

std::size_t tape_bytes(const SubstepTape& t) {
  const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  std::size_t b = bytes(t.before) + bytes(t.svd) + bytes(t.poses) + bytes(t.bins.home) + bytes(t.bins.order) +
      bytes(t.bins.unit_begin) + bytes(t.bins.active) + bytes(t.bins.flag) + bytes(t.grid.active) + bytes(t.grid.mq) +
      bytes(t.grid.v);
  for (const auto& c : t.bins.by_colour) b += bytes(c);
  return b;
}

double run_episode_with_grad(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, std::span<const double> actions,
                             int env_steps, const EpisodeObjective& objective, std::span<double> actions_bar,
                             std::size_t tape_budget) {
  const int adim = model.action_dim();
  const int S = model.config.substeps;
  ws.reserve_reverse(model, env_steps);
  std::fill(actions_bar.begin(), actions_bar.end(), 0.0);
  auto fail = [&] {
    std::fill(actions_bar.begin(), actions_bar.end(), kNaN);
    return kNaN;
  };
  // one env step's tapes before any is measured: the particle buffers, and as much again for the
  // bins and the grid snapshot
  const std::size_t particle_bytes =
      static_cast<std::size_t>(model.particles()) * (sizeof(Particle) + sizeof(SvdRecord));
  if (ws.step_tape_bytes == 0) ws.step_tape_bytes = 2 * particle_bytes * static_cast<std::size_t>(S);

  // forward, keeping the state before every env step and the tapes of the first env steps while
  // they fit the budget
  ws.reset_state(model);
  ws.taped_env_steps = 0;
  std::size_t taped_bytes = 0;
  double loss = 0.0;
  for (int k = 0; k < env_steps; ++k) {
    {
      PhaseClock clock(ws.phase_times);
      copy_in_parts(team, ws.particles, ws.checkpoints[k].particles);
      ws.checkpoints[k].poses = ws.poses;
      clock.lap(&PhaseTimes::other);
    }
    const bool tape = ws.taped_env_steps == k && tape_budget > 0 &&
        (tape_budget == kTapeEverything || taped_bytes + ws.step_tape_bytes <= tape_budget);
    SubstepTape* tapes = tape ? ws.forward_tapes(model, k) : nullptr;
    env_step(model, ws, team, actions.data() + static_cast<std::size_t>(k) * adim, tapes);
    if (tape) {
      std::size_t bytes = 0;
      for (int s = 0; s < S; ++s) bytes += tape_bytes(tapes[s]);
      ws.step_tape_bytes = bytes;
      taped_bytes += bytes;
      ++ws.taped_env_steps;
    }
    if (!state_is_finite(ws.particles, team)) return fail();
    loss += objective.step_loss(k, ws.particles, ws.poses, team);
  }
  if (!std::isfinite(loss)) return fail();

  // reverse: env steps backwards; the state after env step k is the final state or checkpoint k + 1
  zero_adjoints(ws);
  for (int k = env_steps - 1; k >= 0; --k) {
    const bool last = k == env_steps - 1;
    const bool taped = k < ws.taped_env_steps;
    const std::vector<Particle>& after = last ? ws.particles : ws.checkpoints[k + 1].particles;
    const std::vector<Pose>& after_poses = last ? ws.poses : ws.checkpoints[k + 1].poses;
    objective.step_loss_adjoint(k, after, after_poses, ws.adj, ws.pose_adj, team);
    const double* a = actions.data() + static_cast<std::size_t>(k) * adim;
    double* a_bar = actions_bar.data() + static_cast<std::size_t>(k) * adim;
    SubstepTape* tapes = taped ? ws.step_tapes[static_cast<std::size_t>(k)].data() : ws.tapes.data();
    if (!taped) {
      // recompute env step k from its checkpoint, recording its substeps
      PhaseClock clock(ws.phase_times);
      copy_in_parts(team, ws.checkpoints[k].particles, ws.particles);
      ws.poses = ws.checkpoints[k].poses;
      clock.lap(&PhaseTimes::other);
      env_step(model, ws, team, a, tapes);
    }
    // the state each substep produced: the next substep's start, or the state after env step k
    // (for a recomputed step, ws.particles: the end of the recomputation, that same state)
    const std::vector<Particle>& end_of_step = taped ? after : ws.particles;
    for (int s = S - 1; s >= 0; --s)
      substep_adjoint(model, ws, team, a, tapes[s], s + 1 < S ? tapes[s + 1].before : end_of_step, a_bar);
  }
  for (double g : actions_bar)
    if (!std::isfinite(g)) return fail();
  return loss;
}

}  // namespace dsb::mpm
