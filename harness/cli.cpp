#include "harness/cli.hpp"

#include <unistd.h>

#include <charconv>
#include <cstdlib>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <set>
#include <iostream>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "common/error.hpp"
#include "common/usable_cpus.hpp"
#include "common/usable_memory.hpp"
#include "envs/core/lazy_model.hpp"
#include "envs/registry.hpp"
#include "harness/claims_grid.hpp"
#include "harness/commands.hpp"
#include "harness/grid.hpp"
#include "harness/interrupt.hpp"
#include "harness/merge_command.hpp"
#include "harness/output_path.hpp"
#include "harness/plan.hpp"
#include "harness/plan_report.hpp"
#include "harness/render_command.hpp"
#include "harness/report_refresher.hpp"
#include "harness/run_order.hpp"
#include "harness/runner.hpp"
#include "harness/slurm_command.hpp"
#include "harness/store.hpp"
#include "optimizers/registry.hpp"
#include "reference/crosscheck.hpp"

namespace dsb {
namespace {

const char* kVersion = DSB_VERSION;

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
  std::string h = "set a knob of an optimizer's config, OPT.KNOB=VALUE, or an option of an env of the grid, "
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

// the flags that define the grid (also those of `harness slurm`)
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
  app.add_option("--threads", a.threads, "threads inside one run's rollouts and batches (default 1; same results for any value)");
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

// the grid and the jobs of run and plan arguments; every name and number is checked here, before
// any database is opened
struct CheckedRun {
  std::vector<RunSpec> grid;
  Shard shard;
  int jobs = 1;
  std::size_t tape_memory_bytes = 0;
};

// for_this_machine: the grid runs here, so --threads is capped at the CPUs this process may use
// (more threads than CPUs only slow a rollout down; results are the same for any count). `plan`
// passes false: it may plan for another machine.
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
    if (end != a.ext_timeout.c_str() + a.ext_timeout.size() || !(req.ext_timeout_s > 0.0 && req.ext_timeout_s <= 86400.0))
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
    shard = {i, n};
  }
  if (a.db.empty()) throw UsageError("--db must name a file, got ''");
  if (a.jobs < 0 || a.jobs > 1024)
    throw UsageError("--jobs must be from 1 to 1024, or 0 for the CPUs this process may use over --threads, got " +
                     std::to_string(a.jobs));
  if (a.threads < 1 || a.threads > 1024)
    throw UsageError("--threads must be from 1 to 1024, got " + std::to_string(a.threads));
  if (for_this_machine && a.threads > usable_cpus())
    throw UsageError(fmt::format("--threads {} is more than the {} CPUs this process may use (the cap: more threads "
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

PlanContext plan_context(const RunArgs& a, const CheckedRun& run) {
  return {a.db, run.jobs, a.threads, grid_flags(a)};
}

int command_plan(const RunArgs& a, const std::string& runs_csv) {
  const auto start = std::chrono::steady_clock::now();
  const CheckedRun run = check_run_args(a, false);
  std::set<RunKey> done;
  std::map<RunKey, std::string> failed;
  try {
    done = done_keys_of_file(a.db);
    failed = runs_of_file(a.db, "failed");
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
  GridPlan plan = plan_grid(run.grid, done, kVersion, run.shard);
  try {
    if (!a.no_sharing) estimate_sharing(plan, kept_prefixes_of_file(a.db));
    use_measured_walls(plan, measured_walls_of_file(a.db));
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
  const CostModel costs;
  print_plan(std::cout, plan, costs, plan_context(a, run));
  print_failed_runs(std::cout, plan, failed);
  if (!runs_csv.empty()) write_plan_runs_csv(runs_csv, plan, costs, !a.no_sharing, run.jobs);
  const double planning_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << fmt::format("  planned in {:.3f} s; env models built: {} (nothing was written)\n", planning_s,
                           lazy_model_builds());
  return 0;
}

// `harness calibrate [grid flags] [--force]`: times the grid's envs on this machine, caches them
int command_calibrate(const RunArgs& a, bool force) {
  const CheckedRun run = check_run_args(a, false);
  const GridPlan plan = plan_grid(run.grid, {}, kVersion, run.shard);
  CostModel costs;
  std::cout << fmt::format("{:<26} {:>12} {:>12} {:>10}  {}\n", "env", "forward s", "gradient s", "decisions",
                           "source");
  std::map<std::string, EnvOptions> options;  // of each env of the grid (one set per env name)
  for (const auto& spec : run.grid) options[spec.env] = spec.env_options;
  for (const auto& [name, config] : plan.env_configs) {
    EpisodeCost c = costs.episode(name, config.hash);
    const bool measure = force || !c.measured;
    if (measure) {
      std::cerr << "harness: timing " << name << " ..." << std::endl;
      c = costs.calibrate(name, config.hash, run.tape_memory_bytes, options[name]);
      costs.save();  // after each env: an interrupted calibration keeps what it measured
    }
    std::cout << fmt::format("{:<26} {:>12.4g} {:>12.4g} {:>10}  {}\n", name, c.forward_s, c.gradient_s, c.decisions,
                             measure ? "measured now" : "cached");
  }
  std::cout << "cost cache: " << costs.path() << "\n";
  return 0;
}

int command_run(const RunArgs& a, const std::string& report_dir) {
  const CheckedRun run = check_run_args(a, true);
  if (!report_dir.empty()) check_report_folder(report_dir, false, "--report");

  std::unique_ptr<Store> store;
  try {
    store = std::make_unique<Store>(a.db, Provenance{kVersion, DSB_GIT_SHA, host_name()});
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
  GridPlan plan = plan_grid(run.grid, store->done_keys(), kVersion, run.shard);
  if (!a.no_sharing) estimate_sharing(plan, kept_prefixes_of_file(a.db));
  use_measured_walls(plan, measured_walls_of_file(a.db));
  const CostModel costs;
  if (!a.quiet) {
    std::ostringstream text;
    print_plan(text, plan, costs, plan_context(a, run));
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
  const auto s = run_grid(pending, pending_cost, plan.skipped, *store, run.jobs, a.threads, progress,
                          reports ? std::function<void()>([&] { reports->run_finished(); }) : std::function<void()>(),
                          !a.no_sharing, run.tape_memory_bytes);
  if (s.shared_runs > 0)
    std::fprintf(stderr,
                 "harness: %lld runs took %lld episodes from an earlier seed's run (the episodes before the "
                 "optimizer's first draw, replayed: the same bits as simulating them)\n",
                 static_cast<long long>(s.shared_runs), static_cast<long long>(s.shared_episodes));
  if (s.resumed > 0)
    std::fprintf(stderr, "harness: resumed %lld interrupted runs, %lld of their episodes replayed from the database\n",
                 static_cast<long long>(s.resumed), static_cast<long long>(s.replayed_episodes));
  std::fprintf(stderr, "harness: %lld runs in the grid: %lld already done, %lld done now, %lld failed; database %s\n",
               static_cast<long long>(plan.runs), static_cast<long long>(s.skipped), static_cast<long long>(s.done),
               static_cast<long long>(s.failed), a.db.c_str());
  if (reports) reports->final_build();
  if (const int sig = stop_signal(); sig != 0) {
    std::fprintf(stderr,
                 "harness: stopped by %s: %lld runs in progress committed their finished episodes; run the same "
                 "command again to resume them\n",
                 sig == SIGINT ? "SIGINT" : sig == SIGHUP ? "SIGHUP" : "SIGTERM", static_cast<long long>(s.interrupted));
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

// `harness slurm`: the grid is checked like a run's before anything is written; the runs of each
// shard are counted from the run keys (metadata only)
int command_slurm_scripts(const RunArgs& a, const SlurmOptions& options) {
  const CheckedRun run = check_run_args(a, false);
  std::vector<std::int64_t> shard_runs;
  if (options.shards >= 1 && options.shards <= kMaxSlurmShards) {
    shard_runs.assign(options.shards, 0);
    for (const PlannedRun& p : plan_grid(run.grid, {}, kVersion).pending) ++shard_runs[shard_of(p.key, options.shards)];
  }
  // the tasks run in another folder: a target file's path goes to them absolute
  const SlurmGridFlags flags{
      a.all, a.claims, a.envs, a.optimizers, a.seeds, a.budget, settings_with_absolute_paths(a.knobs), a.ext,
      a.ext_timeout};
  SlurmOptions o = options;
  if (o.time.empty() && !shard_runs.empty()) {
    // each task's wall from the plan (its runs over its CPUs, at least its longest run)
    GridPlan plan = plan_grid(run.grid, {}, kVersion);
    estimate_sharing(plan, {});
    const std::vector<double> cost = run_costs(plan, CostModel{});
    std::vector<double> total(static_cast<std::size_t>(o.shards), 0.0), longest(total);
    for (std::size_t i = 0; i < plan.pending.size(); ++i) {
      const auto s = static_cast<std::size_t>(shard_of(plan.pending[i].key, o.shards));
      total[s] += cost[i];
      longest[s] = std::max(longest[s], cost[i]);
    }
    double worst = 0.0;
    for (std::size_t s = 0; s < total.size(); ++s)
      worst = std::max(worst, std::max(total[s] / std::max(1, o.cpus_per_task), longest[s]));
    o.time = slurm_time_limit(worst);
    o.time_note = fmt::format("the plan's longest task, {}, x {} + {} min; --time overrides", human_duration(worst),
                              kSlurmTimeMargin, kSlurmTimeExtraS / 60);
  }
  return command_slurm(flags, run.grid.size(), shard_runs, o, running_binary_path(), std::cout);
}

std::string one_line(std::string s) {
  for (auto& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace

int harness_main(int argc, char** argv) {
  CLI::App app{"diffsim-bench harness: optimizers x differentiable simulators, every episode in SQLite"};
  app.set_version_flag("--version", fmt::format("harness {} (git {}, {} build)", kVersion, DSB_GIT_SHA,
                                                DSB_BUILD_TYPE));
  RunArgs main_args, run_args;
  add_run_options(app, main_args);
  app.require_subcommand(0, 1);

  auto* run = app.add_subcommand("run", "run a grid (also implied by bare flags: harness --all --seeds 5)");
  add_run_options(*run, run_args);

  auto* list = app.add_subcommand("list", "envs (dim, differentiable, rl) and optimizers");

  std::string main_report, run_report;
  app.add_option("--report", main_report,
                 "keep a comparison report of the grid in this folder (new, empty, or an earlier report), rebuilt as "
                 "runs finish");
  run->add_option("--report", run_report,
                  "keep a comparison report of the grid in this folder (new, empty, or an earlier report), rebuilt as "
                  "runs finish");

  RunArgs plan_args;
  auto* plan = app.add_subcommand("plan", "what a grid would run (runs, core-hours per env and family, wall, Slurm), writing nothing");
  add_run_options(*plan, plan_args);
  std::string plan_runs_csv;
  plan->add_option("--runs-csv", plan_runs_csv,
                   "also write each run to run with its estimated seconds and its place in the start order (CSV: "
                   "env,optimizer,seed,budget,planned_s,source,start_rank,lead_seed; a new file)");

  RunArgs calibrate_args;
  bool calibrate_force = false;
  auto* calibrate = app.add_subcommand("calibrate", "time one episode of each env of a grid on this machine (cached for plan and ETAs)");
  add_grid_options(*calibrate, calibrate_args);
  calibrate->add_flag("--force", calibrate_force, "measure again envs already in the cache");

  RunArgs slurm_args;
  SlurmOptions slurm_opts;
  auto* slurm = app.add_subcommand("slurm", "write sbatch scripts that run the grid as a Slurm job array, then merge");
  add_grid_options(*slurm, slurm_args);
  slurm->add_option("--shards", slurm_opts.shards, "array tasks N: task I runs shard I/N")->required();
  slurm->add_option("--dir", slurm_opts.dir, "folder for the scripts, logs, shard databases and results.sqlite")
      ->required();
  slurm->add_option("--cpus-per-task", slurm_opts.cpus_per_task, "CPUs per task, its --jobs (default 1)");
  slurm->add_option("--time", slurm_opts.time, "time limit per task, e.g. 12:00:00 (default: the cluster's)");
  slurm->add_option("--partition", slurm_opts.partition, "Slurm partition (default: the cluster's)");

  std::string eval_env, eval_x;
  std::vector<std::string> eval_sets;
  bool eval_grad = false;
  auto* eval = app.add_subcommand("eval", "one rollout at x, JSON on stdout");
  eval->add_option("--env", eval_env, "env name")->required();
  eval->add_option("--set", eval_sets, "an option of the env, ENV.KEY=VALUE (repeatable; `harness list` shows them)")
      ->type_name("ENV.KEY=VALUE");
  eval->add_option("--x", eval_x, "comma-separated parameters in [-1, 1]")->required();
  eval->add_flag("--grad", eval_grad, "also print dLoss/dx (normalized units)");

  RenderArgs render_args;
  auto* render = app.add_subcommand("render", "pictures of a rollout at a few time points (PNG strip or animated GIF)");
  render->add_option("--env", render_args.env, "env name (a simulated env)")->required();
  render->add_option("--x", render_args.x, "comma-separated parameters in [-1, 1]");
  render->add_option("--best-of", render_args.best_of, "harness database: render the best_x of the env's best done run");
  render->add_option("--out", render_args.out, "FILE.png (frames side by side) or FILE.gif (animation)")->required();
  render->add_option("--frames", render_args.frames, "time points from the start to the end (default 5)");
  render->add_option("--width", render_args.width, "pixels per frame (default 320)");
  render->add_flag("--force", render_args.force, "write over an existing file (never over a database)");

  std::string gc_env;
  GradientSurveyOptions gc;
  bool gc_json = false;
  auto* gradcheck = app.add_subcommand("gradcheck", "analytic gradient vs central differences, with statistics");
  gradcheck->add_option("--env", gc_env, "env name")->required();
  gradcheck->add_option("--points", gc.points, "number of seeded random points (default 3)");
  gradcheck->add_option("--seed", gc.seed, "seed of the points (default 0)");
  gradcheck->add_option("--amplitude", gc.amplitude, "points uniform in [-a, a]^d (default 0.5)");
  gradcheck->add_option("--step", gc.check.step, "central-difference step (default 1e-6)");
  gradcheck->add_option("--tol", gc.check.tolerance, "largest accepted relative error (default 1e-4)");
  gradcheck->add_option("--large-step", gc.large_step,
                        "step along the gradient of the large-step direction check (default 0.05, 0 = off)");
  gradcheck->add_flag("--json", gc_json, "one JSON object (per-point worst errors and the summary)");

  std::string ls_env, ls_dims, ls_center, ls_out;
  int ls_res = 0;
  auto* landscape = app.add_subcommand("landscape", "loss and gradient on an N x N grid over a 2-D slice");
  landscape->add_option("--env", ls_env, "env name")->required();
  landscape->add_option("--dims", ls_dims, "the two coordinates of the slice, I,J (0-based)")->required();
  landscape->add_option("--res", ls_res, "grid points per axis, N")->required();
  landscape->add_option("--center", ls_center, "comma-separated point for the other coordinates (default 0)");
  landscape->add_option("--out", ls_out, "CSV file to write (a new file; see --force)")->required();
  bool ls_force = false;
  landscape->add_flag("--force", ls_force, "write over an existing file (never over a database)");
  GradientCheckOptions ls_check;
  ls_check.step = 0.0;
  landscape->add_option("--check-step", ls_check.step,
                        "also check both gradient components against central differences with this step");
  landscape->add_option("--tol", ls_check.tolerance, "largest accepted relative error of the check (default 1e-4)");

  std::vector<std::string> cc_envs;
  auto* crosscheck = app.add_subcommand("crosscheck", "in-house vs MuJoCo vs Bullet: table of deviations");
  crosscheck->add_option("--env", cc_envs, "rigid envs, comma-separated (default: all five)")->delimiter(',');

  std::string check_db, check_baseline;
  auto* check = app.add_subcommand("check", "regression gate: database result table vs a baseline CSV");
  check->add_option("--db", check_db, "results database")->required();
  check->add_option("--baseline", check_baseline, "baseline CSV (data/baselines/NAME.csv)")->required();

  std::string merge_into;
  std::vector<std::string> merge_inputs;
  auto* merge = app.add_subcommand("merge", "combine shard databases by run key (conflicting runs refused)");
  merge->add_option("--into", merge_into, "the merged database (created or added to)")->required();
  merge->add_option("inputs", merge_inputs, "shard databases to merge")->required();

  std::string export_db, export_out, export_format = "csv";
  auto* exporter = app.add_subcommand(
      "export", "write the database's result table as a baseline CSV, or its runs in IOHprofiler's format");
  exporter->add_option("--db", export_db, "results database")->required();
  exporter->add_option("--out", export_out, "CSV file to write (csv), or a new or empty folder (ioh)")->required();
  exporter->add_option("--format", export_format, "csv (default: the baseline result table) or ioh (IOHanalyzer)");
  bool export_force = false;
  exporter->add_flag("--force", export_force,
                     "write over an existing file, or into a folder with other files (never over a database)");

  std::string report_db = "results.sqlite", report_out = "report", report_landscapes, report_gradient_quality,
              report_renders;
  auto* report = app.add_subcommand("report", "comparison report (index.html, figures, tables) from a database");
  report->add_option("--db", report_db, "results database (default ./results.sqlite)");
  report->add_option("--out", report_out, "output folder (default ./report)");
  report->add_option("--landscapes", report_landscapes, "folder of `harness landscape` CSVs to plot");
  report->add_option("--gradient-quality", report_gradient_quality,
                     "CSV of scripts/gradient-quality.sh (default data/gradient_quality.csv)");
  report->add_option("--renders", report_renders, "folder of scripts/render-best.sh's render_<env>.png to show");
  bool report_force = false;
  report->add_flag("--force", report_force, "write into a folder that holds other files (files of the report's names are replaced)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "harness: error: %s\n", one_line(e.what()).c_str());
    return 2;
  }

  try {
    if (list->parsed()) return command_list();
    if (plan->parsed()) return command_plan(plan_args, plan_runs_csv);
    if (calibrate->parsed()) return command_calibrate(calibrate_args, calibrate_force);
    if (slurm->parsed()) return command_slurm_scripts(slurm_args, slurm_opts);
    if (landscape->parsed())
      return command_landscape(ls_env, ls_dims, ls_res, ls_center, ls_out,
                               landscape->count("--check-step") > 0 ? std::optional(ls_check) : std::nullopt,
                               ls_force);
    if (crosscheck->parsed()) {
      if (!crosscheck_available())
        throw UsageError("crosscheck: this build has neither MuJoCo nor Bullet (DSB_WITH_MUJOCO, DSB_WITH_BULLET)");
      return run_crosscheck(cc_envs, std::cout);
    }
    if (check->parsed()) return command_check(check_db, check_baseline);
    if (merge->parsed()) return command_merge(merge_into, merge_inputs);
    if (exporter->parsed()) return command_export(export_db, export_out, export_format, export_force);
    if (report->parsed()) {
      check_report_folder(report_out, report_force);
      return command_report(report_db, report_out, report_landscapes, false, report_gradient_quality, report_renders);
    }
    if (eval->parsed()) return command_eval(eval_env, eval_x, eval_grad, parse_env_settings(eval_env, eval_sets));
    if (render->parsed()) return command_render(render_args);
    if (gradcheck->parsed())
      return command_gradcheck(gc_env, gc, gc_json);
    return run->parsed() ? command_run(run_args, run_report) : command_run(main_args, main_report);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "harness: error: %s\n", one_line(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harness: failed: %s\n", one_line(e.what()).c_str());
    return 1;
  }
}

}  // namespace dsb
