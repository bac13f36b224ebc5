#include "harness/run/batch_rollouts.hpp"

#include <algorithm>

namespace dsb {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Workspace& WorkspacePool::get(std::size_t slot) {
  if (!workspaces_[slot]) {
    workspaces_[slot] = env_.make_workspace();
    if (slot == 0) workspaces_[slot]->tape_memory_bytes = tape_memory_bytes_;
  }
  return *workspaces_[slot];
}

void run_value_batch(const Env& env, ThreadTeam& team, WorkspacePool& pool, std::span<const double> xs, std::size_t d,
                     std::span<const std::size_t> live, std::vector<RolloutOutcome>& outcomes) {
  const std::size_t slots = std::min<std::size_t>(live.size(), static_cast<std::size_t>(team.size()));
  for (std::size_t s = 0; s < slots; ++s) pool.get(s);  // made here, not on the team's threads
  team.run(static_cast<int>(slots), [&](int slot) {
    Workspace& ws = pool.get(static_cast<std::size_t>(slot));
    for (std::size_t k = static_cast<std::size_t>(slot); k < live.size(); k += slots) {
      const std::size_t i = live[k];
      const auto start = std::chrono::steady_clock::now();
      try {
        outcomes[i].loss = env.loss(xs.subspan(i * d, d), ws, team);
        outcomes[i].metric = env.episode_metric(ws);
      } catch (...) {
        outcomes[i].error = std::current_exception();
      }
      outcomes[i].wall_s = seconds_since(start);
    }
  });
}

}  // namespace dsb
