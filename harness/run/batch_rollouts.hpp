#pragma once
// Rollouts of a run on its thread team: one workspace per team slot, reused for every episode, and
// a batch of value rollouts spread over the slots. Each slot takes every slots-th point with its
// own workspace, serially inside the rollout (a nested parallel loop of the env runs on the slot's
// thread), so the results do not depend on the slot or the team's size.
#include <chrono>
#include <cstddef>
#include <exception>
#include <memory>
#include <span>
#include <vector>

#include "common/thread_team.hpp"
#include "envs/core/env.hpp"

namespace dsb {

double seconds_since(std::chrono::steady_clock::time_point start);

class WorkspacePool {
 public:
  WorkspacePool(const Env& env, int slots) : env_(env), workspaces_(static_cast<std::size_t>(slots)) {}
  // the memory a gradient rollout may keep (Workspace::tape_memory_bytes); gradient rollouts use
  // slot 0 only, so it goes to slot 0; before its first use
  void set_tape_memory(std::size_t bytes) { tape_memory_bytes_ = bytes; }
  // the slot's workspace, made on first use
  Workspace& get(std::size_t slot);

 private:
  const Env& env_;
  std::vector<std::unique_ptr<Workspace>> workspaces_;
  std::size_t tape_memory_bytes_ = 0;
};

struct RolloutOutcome {
  double loss = 0.0, wall_s = 0.0, metric = 0.0;
  std::exception_ptr error;  // what the rollout threw (rethrown in order by the caller)
};

// The value rollouts of the points xs[i*d .. (i+1)*d) for i in `live` into outcomes[i].
void run_value_batch(const Env& env, ThreadTeam& team, WorkspacePool& pool, std::span<const double> xs, std::size_t d,
                     std::span<const std::size_t> live, std::vector<RolloutOutcome>& outcomes);

}  // namespace dsb
