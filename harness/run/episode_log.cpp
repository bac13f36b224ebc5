#include "harness/run/episode_log.hpp"

#include <cmath>
#include <limits>

#include "optimizers/core/diagnostics.hpp"

namespace dsb {

EpisodeLog::EpisodeLog(std::int64_t budget, std::atomic<std::int64_t>* counter)
    : counter_(counter), best_(std::numeric_limits<double>::quiet_NaN()) {
  evals_.reserve(static_cast<std::size_t>(budget));
}

double EpisodeLog::add(std::span<const double> x, double loss, bool used_grad, double wall_s, double metric) {
  const bool failed = !std::isfinite(loss);
  if (failed) {
    loss = std::numeric_limits<double>::quiet_NaN();
    ++failed_;
  } else if (std::isnan(best_) || loss < best_) {
    best_ = loss;
    best_x_.assign(x.begin(), x.end());
  }
  evals_.push_back({static_cast<std::int64_t>(evals_.size()), loss, best_, used_grad, wall_s,
                    failed ? std::numeric_limits<double>::quiet_NaN() : metric});
  if (counter_) counter_->fetch_add(1, std::memory_order_relaxed);
  return failed ? std::numeric_limits<double>::infinity() : loss;
}

void EpisodeLog::add_gradient(std::span<const double> grad) {
  // |g| = sqrt(sum g_i^2), summed in index order
  double sq = 0.0;
  for (double g : grad) sq += g * g;
  grad_norms_.push_back(std::sqrt(sq));
}

nlohmann::json EpisodeLog::diagnostics() const {
  std::int64_t grad_episodes = 0;
  for (const auto& e : evals_) grad_episodes += e.used_grad ? 1 : 0;
  std::int64_t zero = 0;
  for (double g : grad_norms_) zero += g == 0.0 ? 1 : 0;
  nlohmann::json norms = summarize(grad_norms_);
  norms["zero"] = zero;
  return {{"episodes", episodes()},
          {"failed_episodes", failed_},
          {"grad_episodes", grad_episodes},
          {"grad_norms", std::move(norms)}};
}

}  // namespace dsb
