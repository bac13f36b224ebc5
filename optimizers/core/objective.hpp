#pragma once
// What an optimizer sees: a budgeted objective on the normalized box [-1, 1]^dim. The harness
// owns the implementation (counting, recording, stopping); optimizers only call it.
#include <cstdint>
#include <span>
#include <stdexcept>

#include "optimizers/core/work_memo.hpp"

namespace dsb {

// Thrown by an Objective when an optimizer asks for an episode after the budget is spent. The
// runner catches it and ends the run normally; optimizers let it pass through.
struct BudgetExhausted {};

// The per-step view of an RL-capable env, as an RL optimizer sees it: one decision applies its
// action for action_repeat env steps (the seed: 1 on the cartpoles, 5 elsewhere; the last
// decision may cover fewer), so an episode has at most `decisions` of them.
struct RlSpec {
  int observation_dim = 0;
  int action_dim = 0;     // actions in [-1, 1]^action_dim
  int action_repeat = 1;  // env steps per decision
  int decisions = 0;      // ceil(env horizon / action_repeat)
};

// What one decision returns. When `done`, the episode has been recorded as one budget unit and
// `loss` is its final loss (+infinity for a failed episode, as value() gives); the observation is
// the terminal one (what a time-limit bootstrap needs). A simulation that blows up mid-episode
// (a non-finite observation) ends the episode there as a failed one, with an all-zero terminal
// observation: an optimizer never sees NaN.
struct RlStep {
  bool done = false;
  double loss = 0.0;
};

// An Objective is also the run's memo of the optimizer's own work (optimizers/core/work_memo.hpp):
// the harness keeps it in the run's journal, so that a resumed run skips it.
class Objective : public WorkMemo {
 public:
  virtual ~Objective() = default;
  virtual int dim() const = 0;
  virtual bool has_gradient() const = 0;
  virtual std::int64_t budget() const = 0;
  virtual std::int64_t used() const = 0;
  std::int64_t remaining() const { return budget() - used(); }
  // One episode. x must lie in [-1, 1]^dim. A failed episode (simulation blew up) returns
  // +infinity, so it never looks better than a finite loss.
  virtual double value(std::span<const double> x) = 0;
  // One episode with dLoss/dx (normalized units). A failed episode returns +infinity and a zero
  // gradient. Only when has_gradient().
  virtual double value_and_grad(std::span<const double> x, std::span<double> grad) = 0;
  // A batch of episodes (a population): xs holds out.size() points of dim() values each, row
  // after row; out receives what value() would return for each. They are recorded as consecutive
  // episodes in row order, exactly as out.size() calls of value() would be, so the records do
  // not depend on whether or how the implementation evaluates them in parallel. When the budget
  // runs out inside the batch, the points that fit are evaluated and recorded, then
  // BudgetExhausted is thrown. This default evaluates them one at a time.
  virtual void values(std::span<const double> xs, std::span<double> out) {
    const std::size_t d = static_cast<std::size_t>(dim());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = value(xs.subspan(i * d, d));
  }

  // RL episodes, only when has_rl(): the same budget, one unit per finished episode, recorded
  // with its final loss like any other. rl_reset() starts an episode and writes the first
  // observation; it throws BudgetExhausted when no episode is left, and std::logic_error while an
  // episode is still open (every started episode runs to its end and is paid for: no optimizer
  // learns from steps that were never recorded). rl_step() applies one decision (action in the
  // box, checked) and writes the next observation.
  virtual bool has_rl() const { return false; }
  virtual RlSpec rl_spec() const { throw std::logic_error("objective has no RL view"); }
  virtual void rl_reset(std::span<double> /*observation*/) { throw std::logic_error("objective has no RL view"); }
  virtual RlStep rl_step(std::span<const double> /*action*/, std::span<double> /*observation*/) {
    throw std::logic_error("objective has no RL view");
  }
};

}  // namespace dsb
