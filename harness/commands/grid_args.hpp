#pragma once
// The flags that define a grid and how it runs, shared by `run`, `plan`, `calibrate` and `slurm`:
// their storage, their CLI11 options, and the one check of them all (every name and number, before
// any database is opened).
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "harness/commands/command.hpp"
#include "harness/plan/grid.hpp"
#include "harness/plan/plan.hpp"
#include "harness/plan/plan_report.hpp"

namespace CLI {
class App;
}

namespace dsb {

class StoredRuns;

// this binary's harness version (part of every run key)
const char* harness_version();

struct RunArgs {
  bool all = false;
  bool claims = false;  // --claims: the runs the claims table needs (claims_grid.hpp)
  std::vector<std::string> envs, optimizers;
  int seeds = 1;
  std::string budget = "1000";
  std::string db = "results.sqlite";
  int jobs = 0;     // 0 = usable CPUs / threads
  int threads = 1;  // inside one rollout
  std::string shard;
  bool quiet = false;
  std::vector<std::string> knobs;  // --set OPT.KNOB=VALUE or ENV.KEY=VALUE, repeatable
  std::vector<std::string> ext;    // --ext NAME=COMMAND, repeatable
  std::string ext_timeout;         // --ext-timeout SECONDS (empty: the default)
  bool no_sharing = false;         // --no-sharing: simulate every seed's every episode
  std::string tape_memory;         // --tape-memory GB (empty: kTapeMemoryShare of the usable memory over --jobs)
};

// the flags that define the grid (also those of `harness slurm` and `harness calibrate`)
void add_grid_options(CLI::App& app, RunArgs& a);
// the grid's flags and how it runs (database, jobs, threads, shard, ...): `run` and `plan`
void add_run_options(CLI::App& app, RunArgs& a);

// the grid and the jobs of run and plan arguments
struct CheckedRun {
  std::vector<RunSpec> grid;
  Shard shard;
  int jobs = 1;
  std::size_t tape_memory_bytes = 0;
};

// for_this_machine: the grid runs here, so --threads is capped at the CPUs this process may use
// (more threads than CPUs only slow a rollout down; results are the same for any count). `plan`
// passes false: it may plan for another machine. UsageError naming the bad value.
CheckedRun check_run_args(const RunArgs& a, bool for_this_machine);

// what plan's text needs of the arguments: the database, jobs, threads and the grid as flags
PlanContext plan_context(const RunArgs& a, const CheckedRun& run);

// this machine's name, for the runs it stores
std::string host_name();

// The plan of a checked grid against the runs a results file holds: its done runs skipped, the
// episodes its runs keep for other seeds counted (unless --no-sharing) and its measured walls
// used (`run` and `plan`)
GridPlan plan_against(const RunArgs& a, const CheckedRun& run, const StoredRuns& stored);

// Which grid flags a command takes: those of the grid (add_grid_options) or also those of how it
// runs (add_run_options)
enum class GridFlags { grid, run };

// A command over a grid (`run`, `plan`, `calibrate`, `slurm`): its grid flags, then its own
// options (add_own(app, own) binds them to an Own it keeps), and its action, action(args, own),
// run once the command line is parsed.
template <class Own, class AddOwn, class Action>
Command grid_command(std::string name, std::string help, GridFlags flags, AddOwn add_own, Action action) {
  return {std::move(name), std::move(help), [flags, add_own, action](CLI::App& app) {
            auto args = std::make_shared<RunArgs>();
            auto own = std::make_shared<Own>();
            if (flags == GridFlags::run)
              add_run_options(app, *args);
            else
              add_grid_options(app, *args);
            add_own(app, *own);
            return std::function<int()>([args, own, action] { return action(*args, *own); });
          }};
}

}  // namespace dsb
