#pragma once
// What a grid will do before it does it: each run's key (configs resolved once per distinct env
// and optimizer name, from metadata: no env model is built), the shard's runs, and which of them
// are already done in the store (their costs: harness/cost_model.hpp). Used by grid runs and by
// `harness plan`, which writes nothing.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/run_spec.hpp"
#include "harness/store.hpp"

namespace dsb {

struct ResolvedConfig {
  nlohmann::json config;
  std::string hash;
};

struct PlannedRun {
  RunSpec spec;
  RunKey key;
  const ResolvedConfig* env_config;  // owned by the GridPlan
  const ResolvedConfig* opt_config;
};

struct GridPlan {
  std::int64_t runs = 0;            // runs of the grid in this shard
  std::vector<PlannedRun> pending;  // grid order, runs not done yet
  std::int64_t skipped = 0;         // runs already done
  std::int64_t pending_episodes = 0;
  std::map<std::string, ResolvedConfig> env_configs, opt_configs;  // by name
  // per pending run: the share of its episodes expected to come from another seed's run
  // (estimate_sharing); empty when nothing is shared
  std::vector<double> shared_share;
  // per pending run: the median wall seconds of its group's done runs in the database, when it
  // has some that simulated every episode (use_measured_walls); NaN otherwise; empty: none
  std::vector<double> measured_wall_s;
};

// A shard I/N of the grid: the runs whose key hashes to I mod N (shard_of), so adding an env or an
// optimizer, or reordering the names, moves no run to another shard. group_seeds: a sharing
// group's seeds fall in one shard (they share there); false under --no-sharing, where every run
// is cut on its own (a 5-seed group of hours can then run as five slices)
struct Shard {
  int index = 0, count = 1;
  bool group_seeds = true;
};

// the shard of a run: FNV-1a over "env\0optimizer\0seed\0budget\0env_config_hash\0opt_config_hash",
// mixed by splitmix64, mod count (the harness version is not hashed: a new version keeps the cut);
// the seed is left out (an empty string) for optimizers that share across seeds, so that a
// group's seeds share a shard and its later seeds replay the first one's seed-free episodes;
// with group_seeds false (nothing is shared: --no-sharing) every run hashes its own seed
int shard_of(const RunKey& key, int count, bool group_seeds = true);

GridPlan plan_grid(const std::vector<RunSpec>& grid, const std::set<RunKey>& done,
                   const std::string& harness_version, Shard shard = {});

// Sharing across seeds (harness/store.hpp, Store::begin_run): a run of an optimizer that does not
// draw from its start (OptimizerEntry::seed_use) takes the episodes before its first draw from
// another seed's run of its group (the run key but the seed) instead of simulating them.
bool may_share_seeds(const RunSpec& spec);
// "env\0optimizer\0budget\0env config\0optimizer config\0version"
std::string seed_group_of(const RunKey& key);
// For each run of `runs`: the index of its lead (the run of its group with the smallest seed)
// when the run may share and is not the lead itself, else -1. A run waits for its lead.
std::vector<std::ptrdiff_t> share_leads(const std::vector<PlannedRun>& runs);

// Fills plan.shared_share: a pending run that may share takes the seed-free episodes of the
// group's longest prefix kept in the database (`kept`: seed_group_of -> episodes), else, when an
// earlier seed of its group is in the grid, its optimizer's typical seed-free share.
void estimate_sharing(GridPlan& plan, const std::map<std::string, std::int64_t>& kept);
// Fills plan.measured_wall_s from `walls` (seed_group_of -> median wall seconds).
void use_measured_walls(GridPlan& plan, const std::map<std::string, double>& walls);
// the median wall seconds of a database's done runs by group, of the runs that simulated every
// episode (none shared: a shared run's wall is not what its group costs); read-only; nothing
// when the file does not exist
std::map<std::string, double> measured_walls_of_file(const std::string& path);

// the seed-free episodes that done runs of a database keep for other seeds, by group
// (read-only; nothing when the file does not exist or predates sharing)
std::map<std::string, std::int64_t> kept_prefixes_of_file(const std::string& path);

// the runs of an existing database with this status ('done', 'failed'), each with its error
// (empty when it has none); the file is opened read-only (a file that is not a harness database
// throws StoreError); nothing when the file does not exist
std::map<RunKey, std::string> runs_of_file(const std::string& path, const std::string& status);
// the keys of its 'done' runs
std::set<RunKey> done_keys_of_file(const std::string& path);

// Stored runs whose results versions are not this binary's (harness/results_versions.hpp), by env,
// optimizer and reason, of the (env, optimizer) pairs given (all when empty): never resumed or
// counted as done, left in the file as they are. Read-only; nothing when the file does not exist.
struct StaleRuns {
  std::string env, optimizer, reason;
  std::int64_t done = 0, unfinished = 0;  // 'done' runs; 'running' or 'failed' ones
};
std::vector<StaleRuns> stale_runs_of_file(const std::string& path,
                                          const std::set<std::pair<std::string, std::string>>& pairs = {});

}  // namespace dsb
