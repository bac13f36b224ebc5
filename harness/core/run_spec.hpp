#pragma once
// One cell of the grid, resolved: what a run is (env, optimizer, seed, budget, settings) and what
// it runs (the env's shared object, the optimizer's registration or program, both configs and
// this binary's results versions), so that nothing after the grid's expansion looks a name up.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "envs/core/env.hpp"
#include "harness/core/results_versions.hpp"
#include "harness/core/run_result.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/ext/ext_optimizer.hpp"
#include "optimizers/registry.hpp"

namespace dsb {

// a config as a run stores it: its JSON and that JSON's hash (part of the run key)
struct ResolvedConfig {
  nlohmann::json config;
  std::string hash;
};

struct RunSpec {
  std::string env;
  std::string optimizer;
  int seed = 0;                                         // seed index 0..seeds-1
  std::int64_t budget = 0;                              // episodes
  std::uint64_t rng_seed = 0;                           // per-run seed = hash(seed index, env, optimizer)
  std::map<std::string, std::string> knobs = {};        // optimizer knobs set on the command line (--set)
  std::optional<ExtOptimizerSpec> ext = {};             // an external optimizer (ext:NAME), probed
  std::map<std::string, std::string> env_options = {};  // the env's options (--set ENV.KEY=VALUE)

  // resolved once, when the grid expands (plan/grid.hpp, expand_grid): every later step takes
  // these and looks up no name
  std::shared_ptr<const Env> resolved_env = nullptr;  // the env's one object (its model built on first use)
  const OptimizerEntry* entry = nullptr;              // the optimizer's registration; null for ext:NAME
  std::shared_ptr<const ResolvedConfig> env_config = nullptr, opt_config = nullptr;
  ResultsVersions versions = {};  // this binary's, of the env and the optimizer (part of the run key)

  // a fresh optimizer for the run: the registration's (with the knobs), or the external program
  std::unique_ptr<Optimizer> new_optimizer() const;
  // Sharing across seeds (store/store.hpp, Store::begin_run): a run of an optimizer that does not
  // draw from its start (OptimizerEntry::seed_use) takes the episodes before its first draw from
  // another seed's run of its group (the run key but the seed) instead of simulating them.
  bool may_share_seeds() const;
};

// per-run seed: FNV-1a over "env\0optimizer\0seed", mixed once more by splitmix64
std::uint64_t per_run_seed(const std::string& env, const std::string& optimizer, int seed);

}  // namespace dsb
