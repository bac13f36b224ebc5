#include "harness/commands/grid_args.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "common/error.hpp"
#include "common/usable_cpus.hpp"
#include "common/usable_memory.hpp"
#include "envs/registry.hpp"
#include "harness/plan/claims_grid.hpp"
#include "harness/core/shell_word.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/stored_runs.hpp"
#include "optimizers/registry.hpp"

namespace dsb {

const char* harness_version() { return DSB_VERSION; }

namespace {

// the default tape memory of a run: this share of the memory this process may use, over the
// runs at once (a node running one run per core stays clear of swap: the rest is the runs'
// models, checkpoints and the system)
constexpr double kTapeMemoryShare = 0.4;

std::size_t default_tape_memory_bytes(int jobs) {
  return static_cast<std::size_t>(kTapeMemoryShare * static_cast<double>(usable_memory_bytes()) /
                                  static_cast<double>(std::max(1, jobs)));
}

// --set's help: the knobs of every optimizer that has some, and the env options
std::string knob_help() {
  std::string h =
      "set a knob of an optimizer's config, OPT.KNOB=VALUE, or an option of an env of the grid, "
      "ENV.KEY=VALUE (repeatable; the run key keeps variants apart; `harness list` shows both). Env "
      "options:";
  for (const auto& f : env_families())
    for (const auto& o : f.options) h += " " + f.pattern + "." + o.key + ";";
  h += " knobs:";
  for (const auto& e : optimizer_entries()) {
    if (e.knobs.empty()) continue;
    h += " " + e.name + ":";
    for (std::size_t i = 0; i < e.knobs.size(); ++i) h += (i ? "," : "") + e.knobs[i];
    h += ";";
  }
  h.pop_back();
  return h;
}

// the grid of `a` as flags, for commands the plan suggests (shard and db left out)
std::string grid_flags(const RunArgs& a) {
  auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
    return s;
  };
  std::string f = a.all ? "--all" : (a.claims ? "--claims" : "");
  if (!a.envs.empty()) f += (f.empty() ? "" : " ") + std::string("--env ") + join(a.envs);
  if (!a.optimizers.empty()) f += " --optimizer " + join(a.optimizers);
  f += fmt::format(" --seeds {} --budget {}", a.seeds, a.budget);
  for (const auto& k : a.knobs) f += " --set " + shell_word(k);
  for (const auto& x : a.ext) f += " --ext " + shell_word(x);
  if (!a.ext_timeout.empty()) f += " --ext-timeout " + a.ext_timeout;
  return f;
}

}  // namespace

void add_grid_options(CLI::App& app, RunArgs& a) {
  app.add_flag("--all", a.all, "every registered env x every applicable optimizer");
  app.add_flag("--claims", a.claims,
               "exactly the runs the report's claims table needs (reports/paper_claims.csv, compiled in): per claim, "
               "its envs x its optimizers (an 'is best' claim: every optimizer --all pairs with the env); --env "
               "restricts it to those envs");
  app.add_option("--env", a.envs, "env names, comma-separated (see `harness list`)")->delimiter(',');
  app.add_option("--optimizer", a.optimizers, "optimizer names, comma-separated")->delimiter(',');
  app.add_option("--seeds", a.seeds, "number of seeds per (env, optimizer), seed indices 0..N-1");
  app.add_option("--budget", a.budget, "episodes per run (default 1000)");
  app.add_option("--set", a.knobs, knob_help())->type_name("OPT.KNOB=VALUE|ENV.KEY=VALUE");
  app.add_option("--ext", a.ext,
                 "the command of external optimizer ext:NAME, run once per run with /bin/sh -c and spoken to in "
                 "JSON lines (docs/ext-protocol.md); repeatable")
      ->type_name("NAME=COMMAND");
  app.add_option("--ext-timeout", a.ext_timeout,
                 "seconds an external optimizer may take per reply before its run fails (default 60)")
      ->type_name("SECONDS");
}

void add_run_options(CLI::App& app, RunArgs& a) {
  add_grid_options(app, a);
  app.add_option("--db", a.db, "SQLite results file (default ./results.sqlite); resumes");
  app.add_option("--jobs", a.jobs, "runs at once (default: the CPUs this process may use, divided by --threads)");
  app.add_option("--threads", a.threads,
                 "threads inside one run's rollouts and batches (default 1; same results for any value)");
  app.add_option("--shard", a.shard, "run only shard I of N (I/N, 0-based): deterministic slices");
  app.add_flag("--quiet", a.quiet, "no progress lines");
  app.add_option("--tape-memory", a.tape_memory,
                 "GB each run's gradient rollouts may keep to spare recomputing the forward pass (the MPM envs' "
                 "substep tapes; default 40% of the memory this process may use, over --jobs; 0: recompute; the "
                 "same results for any value)")
      ->type_name("GB");
  app.add_flag("--no-sharing", a.no_sharing,
               "simulate every episode of every seed (by default a run replays the episodes an earlier seed's run "
               "simulated before its optimizer's first random draw: the same bits)");
}

std::string host_name() {
  char buf[256] = {0};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

CheckedRun check_run_args(const RunArgs& a, bool for_this_machine) {
  GridRequest req;
  req.all = a.all;
  req.envs = a.envs;
  req.optimizers = a.optimizers;
  req.seeds = a.seeds;
  for (const auto& k : a.knobs) parse_knob_setting(k, req.knobs);
  for (const auto& x : a.ext) parse_ext_setting(x, req.ext);
  if (!a.ext_timeout.empty()) {
    char* end = nullptr;
    req.ext_timeout_s = std::strtod(a.ext_timeout.c_str(), &end);
    if (end != a.ext_timeout.c_str() + a.ext_timeout.size() ||
        !(req.ext_timeout_s > 0.0 && req.ext_timeout_s <= 86400.0))
      throw UsageError("--ext-timeout must be seconds above 0 and at most 86400, got '" + a.ext_timeout + "'");
  }
  {
    // parsed here, not by CLI11, which saturates 99999999999999999999 to INT64_MAX; the range is
    // the grid's to check (grid.cpp), as for every other caller
    std::int64_t b = 0;
    const char* end = a.budget.data() + a.budget.size();
    const auto [ptr, ec] = std::from_chars(a.budget.data(), end, b);
    if (a.budget.empty() || ec != std::errc() || ptr != end)
      throw UsageError("--budget must be a whole number from 1 to " + std::to_string(kMaxBudget) + ", got '" +
                       a.budget + "'");
    req.budget = b;
  }
  Shard shard;
  if (!a.shard.empty()) {
    int i = -1, n = -1;
    char tail = 0;
    if (std::sscanf(a.shard.c_str(), "%d/%d%c", &i, &n, &tail) != 2 || n < 1 || n > 100000 || i < 0 || i >= n)
      throw UsageError("--shard must be I/N with 0 <= I < N <= 100000, got '" + a.shard + "'");
    shard = {i, n, !a.no_sharing};
  }
  check_database_path("--db", a.db, false);  // a FIFO, device or folder is refused before it is opened
  if (a.jobs < 0 || a.jobs > 1024)
    throw UsageError("--jobs must be from 1 to 1024, or 0 for the CPUs this process may use over --threads, got " +
                     std::to_string(a.jobs));
  if (a.threads < 1 || a.threads > 1024)
    throw UsageError("--threads must be from 1 to 1024, got " + std::to_string(a.threads));
  if (for_this_machine && a.threads > usable_cpus())
    throw UsageError(
        fmt::format("--threads {} is more than the {} CPUs this process may use (the cap: more threads "
                    "than CPUs only slow a rollout down; results are the same for any count)",
                    a.threads, usable_cpus()));
  const int jobs = a.jobs > 0 ? a.jobs : std::max(1, usable_cpus() / a.threads);
  std::size_t tape = default_tape_memory_bytes(jobs);
  if (!a.tape_memory.empty()) {
    char* end = nullptr;
    const double gb = std::strtod(a.tape_memory.c_str(), &end);
    if (end != a.tape_memory.c_str() + a.tape_memory.size() || !(gb >= 0.0 && gb <= 1e6))
      throw UsageError("--tape-memory must be gigabytes from 0 to 1000000, got '" + a.tape_memory + "'");
    tape = static_cast<std::size_t>(gb * 1e9);
  }
  std::vector<RunSpec> grid;
  if (a.claims) {
    if (a.all) throw UsageError("--claims and --all: give one of them (--claims is the claims table's part of --all)");
    if (!a.optimizers.empty())
      throw UsageError("--claims takes its optimizers from the claims, got --optimizer " + a.optimizers.front());
    GridRequest base = req;
    base.envs.clear();
    for (const GridRequest& r : claims_requests(base, a.envs)) {
      std::vector<RunSpec> part = expand_grid(r);
      grid.insert(grid.end(), std::make_move_iterator(part.begin()), std::make_move_iterator(part.end()));
    }
  } else {
    grid = expand_grid(req);
  }
  return {std::move(grid), shard, jobs, tape};
}

PlanContext plan_context(const RunArgs& a, const CheckedRun& run) {
  return {a.db, run.jobs, a.threads, grid_flags(a), !a.no_sharing};
}

GridPlan plan_against(const RunArgs& a, const CheckedRun& run, const StoredRuns& stored) {
  GridPlan plan = plan_grid(run.grid, stored.done_keys(), harness_version(), run.shard);
  if (!a.no_sharing) estimate_sharing(plan, stored.kept_prefixes());
  use_measured_walls(plan, stored.measured_walls());
  return plan;
}

}  // namespace dsb
