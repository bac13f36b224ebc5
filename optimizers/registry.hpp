#pragma once
// Optimizers by name; one registration line each in optimizers/registry.cpp.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "optimizers/core/knobs.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/core/optimizer_costs.hpp"

namespace dsb {

// When an optimizer first draws from its run's Rng. Before that draw its episodes are the same
// for every seed, so the harness simulates them once and replays them for the other seeds.
enum class SeedUse {
  at_start,  // draws before its first episode: every episode depends on the seed
  late,      // a deterministic start (the box centre) until a random restart
  never,     // never draws: every seed's run is the same run
};

struct OptimizerEntry {
  std::string name;
  std::string description;
  // The results version (docs/database.md "Results versions"): starts at 1, and the commit that
  // changes what this optimizer does on any env (its proposals, its stopping, its defaults) bumps
  // it. Part of every run key, so runs of an older version are never resumed or counted as done.
  int results_version = 1;
  bool needs_gradient = false;
  std::function<std::unique_ptr<Optimizer>()> make;
  bool needs_rl = false;  // drives the env's per-step view (Objective::rl_*): paired only with RL envs
  // made with knobs set (`--set NAME.KEY=VALUE`); empty for an optimizer without knobs
  std::function<std::unique_ptr<Optimizer>(const KnobSettings&)> make_with = {};
  std::vector<std::string> knobs = {};  // the keys make_with accepts
  SeedUse seed_use = SeedUse::at_start;
  // the mean share of a 1,000-episode run's episodes before its first draw, measured (docs/determinism.md,
  // "Sharing across seeds"): what `harness plan` counts as free for a group's later seeds
  double typical_seed_free_share = 0.0;
  OptimizerCosts costs = {};  // its own work beyond its episodes
};

const std::vector<OptimizerEntry>& optimizer_entries();

// Throws UsageError "unknown optimizer 'NAME'"; with settings, also for an unknown knob, a
// malformed value, or an optimizer without knobs; ConfigError for a value out of range.
std::unique_ptr<Optimizer> make_optimizer(const std::string& name, const KnobSettings& settings = {});
const OptimizerEntry& optimizer_entry(const std::string& name);

}  // namespace dsb
