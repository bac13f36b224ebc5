#pragma once
// The flags that define a grid and how it runs, shared by `run`, `plan`, `calibrate` and `slurm`:
// their storage, their CLI11 options, and the one check of them all (every name and number, before
// any database is opened).
#include <cstddef>
#include <string>
#include <vector>

#include "harness/plan/grid.hpp"
#include "harness/plan/plan.hpp"
#include "harness/plan/plan_report.hpp"

namespace CLI {
class App;
}

namespace dsb {

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

}  // namespace dsb
