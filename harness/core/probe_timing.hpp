#pragma once
// What one timed short run of an (env, optimizer) pair measured (run/probe.hpp times it;
// plan/cost_model.hpp keeps the medians of a pair's timings for the plan).
#include <cstdint>

namespace dsb {

// the run's wall seconds over its episodes, and the seconds per episode of replaying it from its
// journal (0 when the optimizer drew before its first episode: no later seed shares any of it);
// total_s: both together, what the timing cost
struct ProbeTiming {
  std::int64_t episodes = 1;
  double run_s = 0.0, replay_s_per_episode = 0.0, total_s = 0.0;
};

}  // namespace dsb
