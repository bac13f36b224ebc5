#pragma once
// The grid of runs: env x optimizer x seed at one budget, in a canonical order (envs, then
// optimizers, in the order given; seeds ascending). Shards (harness/plan.hpp) are cut from the
// run keys, not from this order.
#include <string>
#include <vector>

#include "harness/run_spec.hpp"

namespace dsb {

struct GridRequest {
  bool all = false;
  std::vector<std::string> envs;        // explicit names (empty with all = every grid env)
  std::vector<std::string> optimizers;  // explicit names (empty with all = every optimizer)
  int seeds = 1;
  std::int64_t budget = 1000;
};

// the largest --budget and --seeds a grid accepts (a run keeps its evals in memory: 48 bytes each)
inline constexpr std::int64_t kMaxBudget = 1'000'000;
inline constexpr int kMaxSeeds = 10'000;

// Validates names and applicability (UsageError naming the bad value) and expands the grid.
// Pairs that are inapplicable (gradient optimizer on a non-differentiable env) are skipped when
// they come from --all and refused when both were named explicitly.
std::vector<RunSpec> expand_grid(const GridRequest& request);

}  // namespace dsb
