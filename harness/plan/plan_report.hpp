#pragma once
// `harness plan`'s text (also printed by a grid run before it starts): runs to do, their
// estimated core-hours per env and per optimizer family (harness/plan/cost_model.hpp), the wall time
// for the given jobs, and the Slurm route for grids bigger than one machine.
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "harness/plan/cost_model.hpp"
#include "harness/plan/plan.hpp"

namespace dsb {

struct PlanContext {
  std::string db;  // the results file
  int jobs = 1, threads = 1;
  std::string grid_flags;  // the grid as command-line flags (for the Slurm command)
  bool share = true;       // sharing across seeds (not --no-sharing): followers wait for their lead
};

// the pending runs' estimated seconds, in plan order
std::vector<double> run_costs(const GridPlan& plan, const CostModel& costs);

// each shard's runs (shard_of, a sharing group's seeds together) at `cost` (run_costs): their sum,
// the longest of them, and the wall a task takes with `jobs` CPUs (runner_wall: a sharing group's
// followers wait for their lead); runs are cut by run-key hash, not by cost, so shards differ
struct ShardCost {
  double seconds = 0.0, longest_run = 0.0, wall = 0.0;
};
std::vector<ShardCost> shard_costs(const GridPlan& plan, const std::vector<double>& cost, int shards, int jobs);

void print_plan(std::ostream& out, const GridPlan& plan, const CostModel& costs, const PlanContext& context);

// `harness plan --runs-csv`: one line per pending run, env,optimizer,seed,budget,planned_s,source,
// start_rank,lead_seed (source: measured when the database's done runs of its group gave it, else
// model; start_rank: its place in the order a grid with these `jobs` starts runs, run_order.hpp;
// lead_seed: the seed whose run it waits for and replays, empty when none), written whole to a
// new file (output_path.hpp)
void write_plan_runs_csv(const std::string& path, const GridPlan& plan, const CostModel& costs, bool share, int jobs);

// the grid's runs that the database holds as 'failed' (`failed`: key -> error, runs_of_file),
// each with its error, at most kFailedRunsShown of them; nothing when there are none
void print_failed_runs(std::ostream& out, const GridPlan& plan, const std::map<RunKey, std::string>& failed);
inline constexpr std::size_t kFailedRunsShown = 50;

// the database's stale runs of the grid's envs and optimizers (stale_runs_of_file), one line per
// env, optimizer and reason; nothing when there are none
void print_stale_runs(std::ostream& out, const std::vector<StaleRuns>& stale);

// the (env, optimizer) pairs of a grid, for stale_runs_of_file
std::set<std::pair<std::string, std::string>> grid_pairs(const std::vector<RunSpec>& grid);

}  // namespace dsb
