#pragma once
// Runs a grid: skips runs already done in the store, executes the rest on `jobs` worker threads
// (each run with its own env, optimizer and RNG, so results do not depend on jobs or order), and
// commits each run with its evals when it ends.
#include <cstdio>
#include <vector>

#include "common/thread_team.hpp"
#include "envs/core/env.hpp"
#include "harness/run_spec.hpp"
#include "harness/store.hpp"
#include "optimizers/core/optimizer.hpp"

namespace dsb {

// One run of an optimizer on an env under the budget wrapper, with `team` (may be null: one
// thread) for the threads inside its rollouts and batches. Never throws for optimizer or
// simulation failures: they become status "failed" with the error text.
RunResult execute_run(const RunSpec& spec, const Env& env, Optimizer& optimizer,
                      std::atomic<std::int64_t>* episode_counter = nullptr, ThreadTeam* team = nullptr);

struct GridSummary {
  std::int64_t skipped = 0, done = 0, failed = 0;
};

// `jobs` runs at once, each with a team of `threads` threads. Runs already done are recognised by
// their keys alone: configs are resolved once per distinct env and optimizer name, and no env
// model is built for a run that is skipped.
GridSummary run_grid(const std::vector<RunSpec>& grid, Store& store, int jobs, int threads,
                     std::FILE* progress_out);

}  // namespace dsb
