#pragma once
// What an optimizer costs beyond its episodes, declared where it is registered
// (optimizers/registry.cpp) so that `harness plan`, the order of a grid and the progress
// line's ETA need no optimizer's name. Seconds on one core of the reference machine (docs/performance.md,
// "Performance": the CPU model there); the harness scales nothing.
#include <cstdint>
#include <functional>
#include <string>

namespace dsb {

struct OptimizerCosts {
  // the plan's family line: "" files it under "gradient episodes" or "forward episodes"
  std::string family;
  // an RL learner's own work per decision (acting and its share of the updates)
  double learner_s_per_decision = 0.0;
  // for an optimizer that needs gradients: the share of its episodes that take one (the others
  // are forward episodes), measured over its runs' diagnostics (objective.grad_episodes / episodes)
  double gradient_share = 1.0;
  // the optimizer's own work over a whole run (a GP's fits and acquisitions) on an env of `dim`
  // parameters at `budget` episodes; empty: negligible beside the episodes
  std::function<double(int dim, std::int64_t budget)> own_seconds = {};
};

}  // namespace dsb
