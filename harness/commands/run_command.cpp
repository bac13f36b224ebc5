// `harness run` (and bare flags: harness --all --seeds 5): runs a grid into the database, resuming
// what an earlier command left, with an optional report kept up to date.
#include <csignal>
#include <functional>
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
#include "harness/store/store.hpp"
#include "harness/commands/cli.hpp"
#include "harness/run/interrupt.hpp"
#include "harness/commands/report_command.hpp"
#include "harness/commands/report_refresher.hpp"
#include "harness/plan/run_order.hpp"
#include "harness/run/runner.hpp"
#include "git_sha.hpp"  // generated at build time: DSB_GIT_SHA

namespace dsb {
namespace {

int command_run(const RunArgs& a, const std::string& report_dir) {
  const CheckedRun run = check_run_args(a, true);
  if (!report_dir.empty()) check_report_folder(report_dir, false, "--report");

  std::unique_ptr<Store> store;
  try {
    store = std::make_unique<Store>(a.db, Provenance{harness_version(), DSB_GIT_SHA, host_name()});
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
  // what the file holds, read once over the store's connection
  const StoredRuns stored = store->runs();
  const GridPlan plan = plan_against(a, run, stored);
  const CostModel costs;
  if (!a.quiet) {
    std::ostringstream text;
    print_plan(text, plan, costs, plan_context(a, run));
    print_stale_runs(text, stored.stale(grid_pairs(run.grid)));
    std::fputs(text.str().c_str(), stderr);
  }
  // cheapest runs first, so partial reports come early, each sharing group's lead pulled ahead of
  // its followers (run_order.hpp; each run's result does not depend on order)
  const std::vector<double> cost = run_costs(plan, costs);
  std::vector<PlannedRun> pending;
  std::vector<double> pending_cost;
  for (const std::size_t i : run_order(plan.pending, cost, !a.no_sharing, run.jobs)) {
    pending.push_back(plan.pending[i]);
    pending_cost.push_back(cost[i]);
  }
  std::FILE* progress = a.quiet ? nullptr : stderr;
  install_stop_handlers();
  std::unique_ptr<ReportRefresher> reports;
  if (!report_dir.empty()) reports = std::make_unique<ReportRefresher>(a.db, report_dir);
  // a sharing group's later seeds wait for its lead (share_leads), in the order they start
  const std::vector<std::ptrdiff_t> leads = a.no_sharing ? std::vector<std::ptrdiff_t>() : share_leads(pending);
  const auto s = run_grid(pending, pending_cost, leads, plan.skipped, *store, run.jobs, a.threads, progress,
                          reports ? std::function<void()>([&] { reports->run_finished(); }) : std::function<void()>(),
                          !a.no_sharing, run.tape_memory_bytes);
  // runs are reported done only if they are in the file the path names
  store->check_path();
  if (s.shared_runs > 0)
    std::fprintf(stderr,
                 "harness: %lld runs took %lld episodes from an earlier seed's run (the episodes before the "
                 "optimizer's first draw, replayed: the same bits as simulating them)\n",
                 static_cast<long long>(s.shared_runs), static_cast<long long>(s.shared_episodes));
  if (s.resumed > 0)
    std::fprintf(stderr,
                 "harness: resumed %lld interrupted runs, %lld of their episodes replayed from the database; their "
                 "optimizers' own work (GP fits, acquisitions): %lld results recalled, %lld computed again\n",
                 static_cast<long long>(s.resumed), static_cast<long long>(s.replayed_episodes),
                 static_cast<long long>(s.recalled_work), static_cast<long long>(s.recomputed_work));
  std::fprintf(stderr, "harness: %lld runs in the grid: %lld already done, %lld done now, %lld failed; database %s\n",
               static_cast<long long>(plan.runs), static_cast<long long>(s.skipped), static_cast<long long>(s.done),
               static_cast<long long>(s.failed), a.db.c_str());
  if (reports) reports->final_build();
  if (const int sig = stop_signal(); sig != 0) {
    std::fprintf(stderr,
                 "harness: stopped by %s: %lld runs in progress committed their finished episodes; run the same "
                 "command again to resume them\n",
                 sig == SIGINT       ? "SIGINT"
                     : sig == SIGHUP ? "SIGHUP"
                                     : "SIGTERM",
                 static_cast<long long>(s.interrupted));
    return 128 + sig;
  }
  if (s.failed > 0) {
    std::fprintf(stderr,
                 "harness: %lld runs failed (exit status %d); they are stored with their errors, `harness plan` with "
                 "the same flags and --db lists them, and the same command runs them again\n",
                 static_cast<long long>(s.failed), kExitRunsFailed);
    return kExitRunsFailed;
  }
  return 0;
}

}  // namespace

Command run_command() {
  return grid_command<std::string>(
      "run", "run a grid (also implied by bare flags: harness --all --seeds 5)", GridFlags::run,
      [](CLI::App& app, std::string& report) {
        app.add_option("--report", report,
                       "keep a comparison report of the grid in this folder (new, empty, or an earlier report), "
                       "rebuilt as runs finish");
      },
      command_run);
}

}  // namespace dsb
