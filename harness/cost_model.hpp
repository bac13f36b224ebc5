#pragma once
// What a run costs, before it runs: seconds per episode of each env on this machine, by kind of
// episode (forward, gradient, RL with the learner's own time), for `harness plan`, the order of a
// grid (cheap runs first) and the progress line's ETA.
//
// Costs come from `harness calibrate`, which times episodes of each env at the centre of its box
// and caches them per machine (the CPU's model name), harness version and env config hash in
// $DSB_COST_CACHE, else $XDG_CACHE_HOME/diffsim-bench/episode-costs.json, else
// ~/.cache/diffsim-bench/episode-costs.json. Envs not measured yet fall back to their cost hint
// (seconds of a gradient episode on the machine the hint was written on), and the plan says so.
// Reading the cache never builds an env model.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "envs/core/env.hpp"
#include "envs/core/env_options.hpp"
#include "harness/plan.hpp"

namespace dsb {

struct EpisodeCost {
  double forward_s = 0.0;   // one loss() rollout
  double gradient_s = 0.0;  // one loss_and_grad() rollout (= forward_s when not differentiable)
  int decisions = 0;        // RL decisions per episode (0: no RL view)
  bool measured = false;    // false: from the env's cost hint
};

class CostModel {
 public:
  // loads the cache (a missing or unreadable cache is empty)
  CostModel();

  // the cost of one episode of `env_name` (config hash as stored with runs)
  EpisodeCost episode(const std::string& env_name, const std::string& env_config_hash) const;
  // the estimated seconds of a whole run on one core, `shared_share` of its episodes taken from
  // another seed's run (replayed: free)
  double run_seconds(const PlannedRun& run, double shared_share = 0.0) const;

  // times one forward and one gradient episode of the env (repeated to at least 0.2 s for cheap
  // envs: the median is kept; the gradient with `tape_memory_bytes` as a run has them) and its RL
  // view's decisions, and records them; `env_options` as the grid gives the env (--set ENV.KEY=VALUE)
  EpisodeCost calibrate(const std::string& env_name, const std::string& env_config_hash,
                        std::size_t tape_memory_bytes = 0, const EnvOptions& env_options = {});
  // writes the cache (creating its folder); throws UsageError naming the file when it cannot
  void save() const;

  const std::string& path() const { return path_; }

 private:
  std::string key(const std::string& env_name, const std::string& env_config_hash) const;
  std::string path_, cpu_;
  std::map<std::string, EpisodeCost> table_;
};

// the CPU's model name (/proc/cpuinfo), "unknown" when it cannot be read
std::string cpu_model_name();

// "3.2 h", "41 min", "12 s", "4.5 days"
std::string human_duration(double seconds);

}  // namespace dsb
