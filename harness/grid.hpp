#pragma once
// The grid of runs: env x optimizer x seed at one budget, in a canonical order (envs, then
// optimizers, in the order given; seeds ascending). Shards (harness/plan.hpp) are cut from the
// run keys, not from this order.
#include <map>
#include <string>
#include <vector>

#include "harness/run_spec.hpp"
#include "optimizers/core/knobs.hpp"

namespace dsb {

struct GridRequest {
  bool all = false;
  std::vector<std::string> envs;        // explicit names (empty with all = every grid env)
  std::vector<std::string> optimizers;  // explicit names (empty with all = every optimizer)
  int seeds = 1;
  std::int64_t budget = 1000;
  std::map<std::string, KnobSettings> knobs;  // optimizer -> knob -> value (--set OPT.KEY=VALUE)
};

// "boleap.sigma0=0.3" into knobs["boleap"]["sigma0"] = "0.3"; UsageError naming a malformed one
void parse_knob_setting(const std::string& text, std::map<std::string, KnobSettings>& knobs);

// the largest --budget and --seeds a grid accepts (a run keeps its evals in memory: 48 bytes each)
inline constexpr std::int64_t kMaxBudget = 1'000'000;
inline constexpr int kMaxSeeds = 10'000;

// Validates names and applicability (UsageError naming the bad value) and expands the grid.
// Knobs must name an optimizer of the grid and are checked by building it once.
// Pairs that are inapplicable (gradient optimizer on a non-differentiable env) are skipped when
// they come from --all and refused when both were named explicitly.
std::vector<RunSpec> expand_grid(const GridRequest& request);

}  // namespace dsb
