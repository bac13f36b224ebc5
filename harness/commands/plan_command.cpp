// `harness plan`: what a grid would run (runs, core-hours per env and family, wall, Slurm), writing nothing.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "common/error.hpp"
#include "envs/core/lazy_model.hpp"
#include "harness/commands/command.hpp"
#include "harness/plan/cost_model.hpp"
#include "harness/commands/grid_args.hpp"
#include "harness/plan/plan.hpp"
#include "harness/plan/plan_report.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/stored_runs.hpp"

namespace dsb {
namespace {

int command_plan(const RunArgs& a, const std::string& runs_csv) {
  const auto start = std::chrono::steady_clock::now();
  const CheckedRun run = check_run_args(a, false);
  // the database, opened once and read-only (nothing when it does not exist)
  GridPlan plan;
  std::map<RunKey, std::string> failed;
  std::vector<StaleRuns> stale;
  try {
    const StoredRunsFile file(a.db);
    const StoredRuns& stored = file.runs();
    failed = stored.with_status("failed");
    plan = plan_against(a, run, stored);
    stale = stored.stale(grid_pairs(run.grid));
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
  const CostModel costs;
  print_plan(std::cout, plan, costs, plan_context(a, run));
  print_failed_runs(std::cout, plan, failed);
  print_stale_runs(std::cout, stale);
  if (!runs_csv.empty()) write_plan_runs_csv(runs_csv, plan, costs, !a.no_sharing, run.jobs);
  const double planning_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << fmt::format("  planned in {:.3f} s; env models built: {} (nothing was written)\n", planning_s,
                           lazy_model_builds());
  return 0;
}

}  // namespace

Command plan_command() {
  return grid_command<std::string>(
      "plan", "what a grid would run (runs, core-hours per env and family, wall, Slurm), writing nothing",
      GridFlags::run,
      [](CLI::App& app, std::string& runs_csv) {
        app.add_option("--runs-csv", runs_csv,
                       "also write each run to run with its estimated seconds and its place in the start order "
                       "(CSV: env,optimizer,seed,budget,planned_s,source,start_rank,lead_seed; a new file)");
      },
      command_plan);
}

}  // namespace dsb
