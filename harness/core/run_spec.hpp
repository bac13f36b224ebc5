#pragma once
// One cell of the grid and what a finished run produced.
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/replay.hpp"
#include "harness/core/run_status.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/ext/ext_optimizer.hpp"

namespace dsb {

// a config as a run stores it: its JSON and that JSON's hash (part of the run key)
struct ResolvedConfig {
  nlohmann::json config;
  std::string hash;
};

struct RunSpec {
  std::string env;
  std::string optimizer;
  int seed = 0;              // seed index 0..seeds-1
  std::int64_t budget = 0;   // episodes
  std::uint64_t rng_seed = 0;  // per-run seed = hash(seed index, env, optimizer)
  std::map<std::string, std::string> knobs = {};  // optimizer knobs set on the command line (--set)
  std::optional<ExtOptimizerSpec> ext = {};  // an external optimizer (ext:NAME), probed
  std::map<std::string, std::string> env_options = {};  // the env's options (--set ENV.KEY=VALUE)
};

// per-run seed: FNV-1a over "env\0optimizer\0seed", mixed once more by splitmix64
std::uint64_t per_run_seed(const std::string& env, const std::string& optimizer, int seed);

// the optimizer of one run: the registry's (with its knobs), or the external program of spec.ext
std::unique_ptr<Optimizer> make_run_optimizer(const RunSpec& spec);

// Sharing across seeds (store/store.hpp, Store::begin_run): a run of an optimizer that does not
// draw from its start (OptimizerEntry::seed_use) takes the episodes before its first draw from
// another seed's run of its group (the run key but the seed) instead of simulating them.
bool may_share_seeds(const RunSpec& spec);

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
