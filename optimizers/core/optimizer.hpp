#pragma once
// Optimizer contract: minimize a budgeted Objective with a seeded RNG; deterministic given the
// seed. Optimizers keep asking until the objective throws BudgetExhausted (or return early when
// they have nothing left to try). Hyperparameters live in a config struct, stored with each run.
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "common/rng.hpp"
#include "optimizers/core/objective.hpp"

namespace dsb {

class Optimizer {
 public:
  virtual ~Optimizer() = default;
  virtual const std::string& name() const = 0;
  virtual bool needs_gradient() const = 0;
  virtual nlohmann::json config() const = 0;
  virtual void minimize(Objective& f, Rng& rng) = 0;
};

}  // namespace dsb
