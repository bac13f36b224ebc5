// `harness calibrate`: times one episode of each env of a grid on this machine, and a short run of
// each cheap (env, optimizer) pair (cached for plan and ETAs).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "common/error.hpp"
#include "envs/core/lazy_model.hpp"
#include "harness/commands/command.hpp"
#include "harness/plan/cost_model.hpp"
#include "harness/commands/grid_args.hpp"
#include "harness/plan/plan.hpp"
#include "harness/plan/plan_report.hpp"
#include "harness/run/probe.hpp"

namespace dsb {
namespace {

// `harness calibrate [grid flags] [--force]`: times the grid's envs on this machine, caches them
int command_calibrate(const RunArgs& a, bool force) {
  const CheckedRun run = check_run_args(a, false);
  const GridPlan plan = plan_grid(run.grid, {}, harness_version(), run.shard);
  CostModel costs;
  std::cout << fmt::format("{:<26} {:>12} {:>12} {:>10}  {}\n", "env", "forward s", "gradient s", "decisions",
                           "source");
  std::map<std::string, const RunSpec*> envs;  // the first run of each env of the grid, by name
  for (const auto& spec : run.grid) envs.emplace(spec.env, &spec);
  for (const auto& [name, spec] : envs) {
    EpisodeCost c = costs.episode(*spec);
    const bool measure = force || !c.measured;
    if (measure) {
      std::cerr << "harness: timing " << name << " ..." << std::endl;
      c = costs.calibrate(*spec, run.tape_memory_bytes);
      costs.save();  // after each env: an interrupted calibration keeps what it measured
    }
    std::cout << fmt::format("{:<26} {:>12.4g} {:>12.4g} {:>10}  {}\n", name, c.forward_s, c.gradient_s, c.decisions,
                             measure ? "measured now" : "cached");
  }
  // the cheap pairs' short runs (CostModel: an optimizer's own work per episode), one per
  // (env, optimizer, configs), timed in rounds across the pairs as a grid runs them
  std::set<std::string> probed;
  std::vector<PlannedRun> pairs;
  std::vector<bool> measured_now;
  for (const PlannedRun& run : plan.pending) {
    const std::string pair =
        run.spec.env + "|" + run.key.env_config_hash + "|" + run.spec.optimizer + "|" + run.key.opt_config_hash;
    if (!costs.probes(run) || !probed.insert(pair).second) continue;
    pairs.push_back(run);
    measured_now.push_back(force || !costs.probed(run));
  }
  std::vector<PlannedRun> to_time;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (measured_now[i]) to_time.push_back(pairs[i]);
  costs.calibrate_runs(
      to_time, time_probe,
      [](const PlannedRun& run) {
        std::cerr << "harness: timing a short run of " << run.spec.env << " x " << run.spec.optimizer << " ..."
                  << std::endl;
      },
      [&costs] { costs.save(); });
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const PlannedRun& run = pairs[i];
    if (i == 0)
      std::cout << fmt::format("\n{:<26} {:<16} {:>9} {:>12}  {}\n", "env", "optimizer", "episodes", "seconds",
                               "source");
    const RunProbe p = *costs.probed(run);
    std::cout << fmt::format("{:<26} {:<16} {:>9} {:>12.4g}  {}\n", run.spec.env, run.spec.optimizer, p.episodes,
                             p.seconds, measured_now[i] ? "measured now" : "cached");
  }
  std::cout << "cost cache: " << costs.path() << "\n";
  return 0;
}

}  // namespace

Command calibrate_command() {
  return grid_command<bool>(
      "calibrate", "time one episode of each env of a grid on this machine (cached for plan and ETAs)", GridFlags::grid,
      [](CLI::App& app, bool& force) { app.add_flag("--force", force, "measure again envs already in the cache"); },
      command_calibrate);
}

}  // namespace dsb
