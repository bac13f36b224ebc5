#pragma once
// Optimizer contract: minimize a budgeted Objective with a seeded RNG; deterministic given the
// seed. Optimizers keep asking until the objective throws BudgetExhausted (or return early when
// they have nothing left to try). Hyperparameters live in a config struct, stored with each run.
// What an optimizer learned about its last run (restarts, stop reasons, model fits) is reported
// by diagnostics() and stored with the run as JSON (runs.diagnostics).
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
  // What the last minimize() did, as a small JSON object (a few KB at most: lists capped with
  // optimizers/core/diagnostics.hpp). Filled while minimize() runs, so it is complete when
  // minimize() ends by BudgetExhausted or another exception; reset by the next minimize().
  // Deterministic given the seed: no timings, no addresses. Default: an empty object.
  virtual nlohmann::json diagnostics() const { return nlohmann::json::object(); }
  // The CPU seconds so far of the processes this optimizer started for its current or last
  // minimize() (an external program and what it started: ext_optimizer.hpp), read from the
  // thread that runs minimize(); 0 for one that computes only in that thread. The runner adds it
  // to the run's own CPU (runs.cpu_s).
  virtual double process_cpu_s() const { return 0.0; }
};

}  // namespace dsb
