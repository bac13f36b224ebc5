#pragma once
// What a run produced: its episodes as recorded, and the run's end (status, best, diagnostics,
// and what sharing and resume need).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/replay.hpp"
#include "harness/core/run_status.hpp"

namespace dsb {

struct EvalRecord {
  std::int64_t episode = 0;  // 0-based
  double loss = 0.0;         // NaN for a failed episode (stored as NULL)
  double best_loss = 0.0;    // best finite loss so far (NaN while none)
  bool used_grad = false;
  double wall_s = 0.0;
  double metric = std::numeric_limits<double>::quiet_NaN();  // optional second metric (NULL when NaN)
};

struct RunResult {
  RunStatus status = RunStatus::done;  // done or failed (execute_run also: interrupted, diverged)
  std::int64_t episodes = 0;
  std::int64_t failed_episodes = 0;
  double best_loss = 0.0;  // NaN when no episode succeeded
  std::vector<double> best_x;
  double wall_s = 0.0;
  // the CPU seconds the harness's threads spent on the run over all its sessions (runs.cpu_s); NaN
  // when unknown (a thread team's workers are not measured; a session before schema 6)
  double cpu_s = std::numeric_limits<double>::quiet_NaN();
  std::string error;
  std::vector<EvalRecord> evals;
  // {"optimizer": Optimizer::diagnostics(), "objective": BudgetedObjective::diagnostics()};
  // stored as runs.diagnostics (JSON); deterministic, no timings
  nlohmann::json diagnostics;
  std::int64_t replayed_episodes = 0;  // episodes answered from a resumed run's journal (not stored)
  // results of the optimizer's own work (GP fits, acquisitions) recalled from that journal, and
  // computed again while it was served (a journal written without them); not stored
  std::int64_t recalled_work = 0, recomputed_work = 0;
  // the episodes before the optimizer's first draw, and the journal entries not committed yet
  // (from journal_tail_first_seq on): a done run keeps its seed-free prefix for other seeds
  SeedFreePrefix seed_free;
  std::vector<ReplayEntry> journal_tail;
  std::int64_t journal_tail_first_seq = 0;
};

}  // namespace dsb
