#pragma once
// The budget wrapper: the only way an optimizer reaches an env. It checks every point (size, in
// the box, finite), counts and records every episode, keeps the best, turns a blown-up
// simulation into a failed episode, and throws BudgetExhausted once the budget is spent.
// Rollouts reuse workspaces made once per run (one per thread of the run's team); a batch is
// spread over the team, one rollout per thread at a time, and recorded in batch order.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/thread_team.hpp"
#include "envs/core/env.hpp"
#include "harness/run_spec.hpp"
#include "optimizers/core/objective.hpp"

namespace dsb {

class BudgetedObjective : public Objective {
 public:
  // episode_counter (may be null) is incremented after every episode, for progress lines; team
  // (may be null: one thread) runs the threads inside a rollout and the points of a batch
  BudgetedObjective(const Env& env, std::int64_t budget,
                    std::atomic<std::int64_t>* episode_counter = nullptr, ThreadTeam* team = nullptr);

  int dim() const override { return env_.dim(); }
  bool has_gradient() const override { return env_.differentiable(); }
  std::int64_t budget() const override { return budget_; }
  std::int64_t used() const override { return static_cast<std::int64_t>(evals_.size()); }
  double value(std::span<const double> x) override;
  double value_and_grad(std::span<const double> x, std::span<double> grad) override;
  void values(std::span<const double> xs, std::span<double> out) override;
  bool has_rl() const override { return env_.supports_rl(); }
  RlSpec rl_spec() const override;
  void rl_reset(std::span<double> observation) override;
  RlStep rl_step(std::span<const double> action, std::span<double> observation) override;

  const std::vector<EvalRecord>& evals() const { return evals_; }
  double best_loss() const { return best_; }  // NaN while no episode succeeded
  const std::vector<double>& best_x() const { return best_x_; }
  std::int64_t failed_episodes() const { return failed_; }
  // What the objective side saw (the "objective" half of runs.diagnostics): {"episodes",
  // "failed_episodes", "grad_episodes" (episodes with a gradient, failed ones included),
  // "grad_norms": summary of the Euclidean norms of the finite gradients (failed episodes have
  // none) with "zero" (how many were exactly 0)}.
  nlohmann::json diagnostics() const;

 private:
  void check_point(std::span<const double> x) const;
  Workspace& workspace(std::size_t slot);
  double record(std::span<const double> x, double loss, bool used_grad, double wall_s, double metric);

  const Env& env_;
  std::int64_t budget_;
  std::atomic<std::int64_t>* counter_;
  ThreadTeam& team_;
  std::vector<std::unique_ptr<Workspace>> workspaces_;  // one per team thread, made on first use
  std::vector<EvalRecord> evals_;
  double best_;
  std::vector<double> best_x_;
  std::int64_t failed_ = 0;
  std::vector<double> grad_norms_;  // |dLoss/dx| of every gradient episode that did not fail
  // RL: the env's per-step view (made on first use), the open episode's start and env steps
  RlEnv& rl_env();
  void write_observation(std::span<double> observation) const;
  std::unique_ptr<RlEnv> rl_;
  bool rl_open_ = false;
  std::chrono::steady_clock::time_point rl_start_{};
};

}  // namespace dsb
