#pragma once
// Runs a grid: skips runs already done in the store, executes the rest on `jobs` worker threads
// (each run with its own env, optimizer and RNG, so results do not depend on jobs or order),
// commits each run's episodes as it goes (every kCommitIntervalS) and the run when it ends. A run
// an earlier harness left unfinished resumes by replaying its journal (harness/core/replay.hpp). A stop
// request (harness/run/interrupt.hpp) ends every run after its current episode, committed.
#include <cstdio>
#include <functional>
#include <vector>

#include "common/thread_team.hpp"
#include "envs/core/env.hpp"
#include "harness/core/run_key.hpp"
#include "harness/core/run_spec.hpp"
#include "harness/run/budget.hpp"
#include "harness/store/store.hpp"
#include "optimizers/core/optimizer.hpp"

namespace dsb {

// One run of an optimizer on an env under the budget wrapper, with `team` (may be null: one
// thread) for the threads inside its rollouts and batches. Never throws for optimizer or
// simulation failures: they become status "failed" with the error text.
// With `control`, the run journals every call to control->listener, serves control->journal
// first (a resume), and stops when *control->stop is set: status "interrupted" (nothing final to
// store), or "diverged" when the journal does not fit the run (start it again without it).
struct RunControl {
  EpisodeListener* listener = nullptr;
  const std::atomic<bool>* stop = nullptr;
  std::vector<ReplayEntry> journal;
  std::int64_t journal_episodes = 0;
  std::size_t tape_memory_bytes = 0;  // Workspace::tape_memory_bytes of the run
};
RunResult execute_run(const RunSpec& spec, const Env& env, Optimizer& optimizer,
                      std::atomic<std::int64_t>* episode_counter = nullptr, ThreadTeam* team = nullptr,
                      RunControl* control = nullptr);

// seconds between commits of a running run's episodes
inline constexpr double kCommitIntervalS = 2.0;

struct GridSummary {
  std::int64_t skipped = 0, done = 0, failed = 0;
  std::int64_t interrupted = 0;        // runs stopped by a signal, committed, to resume
  std::int64_t resumed = 0;            // runs that resumed an earlier attempt
  std::int64_t replayed_episodes = 0;  // episodes those served from their journals
  std::int64_t recalled_work = 0;      // results of their optimizers' own work recalled from them
  std::int64_t recomputed_work = 0;    // and computed again while they were served
  std::int64_t shared_runs = 0;        // runs that took episodes from another seed's run
  std::int64_t shared_episodes = 0;    // those episodes
};

// `jobs` runs at once, each with a team of `threads` threads. Runs already done are recognised by
// their keys alone: configs are resolved once per distinct env and optimizer name, and no env
// model is built for a run that is skipped.
// `pending` in the order to run them; `run_cost_s` their estimated seconds (the progress line's
// ETA); on_run_finished (may be empty) is called after every run that ends (done or failed).
// With `share` (the default; --no-sharing turns it off), runs share their seed-free episodes
// across seeds (Store::begin_run): a run of a sharing group waits until its lead has ended
// (`leads`: per run the index of its lead, or -1; plan/plan.hpp's share_leads; empty: none waits),
// and a worker takes the first run in order that is free to start. Sharing changes no result: a
// shared episode is the same bits as simulating it.
// tape_memory_bytes: what each run's gradient rollouts may keep (Workspace::tape_memory_bytes).
GridSummary run_grid(const std::vector<PlannedRun>& pending, const std::vector<double>& run_cost_s,
                     const std::vector<std::ptrdiff_t>& leads, std::int64_t skipped, Store& store, int jobs,
                     int threads, std::FILE* progress_out, const std::function<void()>& on_run_finished = {},
                     bool share = true, std::size_t tape_memory_bytes = 0);

}  // namespace dsb
