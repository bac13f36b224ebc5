#pragma once
// What a grid will do before it does it: each run's key (from its spec, resolved when the grid
// expanded: plan/grid.hpp), the shard's runs, and which of them
// are already done in the store (their costs: harness/plan/cost_model.hpp). Used by grid runs and by
// `harness plan`, which writes nothing.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/run_key.hpp"
#include "harness/core/run_spec.hpp"

namespace dsb {

struct GridPlan {
  std::int64_t runs = 0;            // runs of the grid in this shard
  std::vector<PlannedRun> pending;  // grid order, runs not done yet
  std::int64_t skipped = 0;         // runs already done
  std::int64_t pending_episodes = 0;
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
int shard_of(const PlannedRun& run, int count, bool group_seeds = true);

GridPlan plan_grid(const std::vector<RunSpec>& grid, const std::set<RunKey>& done, const std::string& harness_version,
                   Shard shard = {});

// For each run of `runs`: the index of its lead (the run of its group, RunKey::group, with the smallest seed)
// when the run may share and is not the lead itself, else -1. A run waits for its lead, except where
// its group's donor is stored (PlannedRun::donor_stored: a resumed grid whose lead is done), where
// every seed replays from the database at once.
std::vector<std::ptrdiff_t> share_leads(const std::vector<PlannedRun>& runs);

// Fills plan.shared_share: a pending run that may share takes the seed-free episodes of the
// group's longest prefix kept in the database (`kept`: RunKey::group -> episodes, store/stored_runs.hpp), else, when an
// earlier seed of its group is in the grid, its optimizer's typical seed-free share. Marks the runs
// of a group with a kept prefix PlannedRun::donor_stored.
void estimate_sharing(GridPlan& plan, const std::map<std::string, std::int64_t>& kept);
// Fills plan.measured_wall_s from `walls` (RunKey::group -> median wall seconds).
void use_measured_walls(GridPlan& plan, const std::map<std::string, double>& walls);

}  // namespace dsb
