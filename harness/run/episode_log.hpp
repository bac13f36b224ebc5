#pragma once
// The record of a run's episodes: every episode in order with the best loss so far, the best
// point, the failed episodes (a non-finite loss is stored as NaN and shown to the optimizer as
// +inf) and the norms of the gradients the run was given. What the runner stores.
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/run_spec.hpp"

namespace dsb {

class EpisodeLog {
 public:
  // counter (may be null) is incremented after every episode, for progress lines
  EpisodeLog(std::int64_t budget, std::atomic<std::int64_t>* counter);

  // Records one finished episode at x (empty for an RL episode) and returns the loss the
  // optimizer sees: the loss, or +inf when it is not finite (a failed episode, stored as NaN with
  // a NaN metric).
  double add(std::span<const double> x, double loss, bool used_grad, double wall_s, double metric);
  // the Euclidean norm of a finite gradient the run was given (summed in index order)
  void add_gradient(std::span<const double> grad);

  std::int64_t episodes() const { return static_cast<std::int64_t>(evals_.size()); }
  const std::vector<EvalRecord>& evals() const { return evals_; }
  double best_loss() const { return best_; }  // NaN while no episode succeeded
  const std::vector<double>& best_x() const { return best_x_; }
  std::int64_t failed_episodes() const { return failed_; }
  // {"episodes", "failed_episodes", "grad_episodes" (episodes with a gradient, failed ones
  // included), "grad_norms": summary of the finite gradients' norms with "zero" (how many were 0)}
  nlohmann::json diagnostics() const;

 private:
  std::atomic<std::int64_t>* counter_;
  std::vector<EvalRecord> evals_;
  double best_;
  std::vector<double> best_x_;
  std::int64_t failed_ = 0;
  std::vector<double> grad_norms_;
};

}  // namespace dsb
