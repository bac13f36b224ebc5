#include "harness/budget.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "optimizers/core/diagnostics.hpp"

namespace dsb {

BudgetedObjective::BudgetedObjective(const Env& env, std::int64_t budget,
                                     std::atomic<std::int64_t>* episode_counter)
    : env_(env), budget_(budget), counter_(episode_counter),
      best_(std::numeric_limits<double>::quiet_NaN()) {
  evals_.reserve(static_cast<std::size_t>(budget));
}

void BudgetedObjective::check_point(std::span<const double> x) const {
  if (static_cast<int>(x.size()) != env_.dim())
    throw std::logic_error("optimizer asked for a point of dimension " + std::to_string(x.size()) +
                           " on env '" + env_.name() + "' of dimension " + std::to_string(env_.dim()));
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!(x[i] >= -1.0 && x[i] <= 1.0))
      throw std::logic_error("optimizer asked for x[" + std::to_string(i) + "] = " +
                             std::to_string(x[i]) + " outside [-1, 1]");
}

double BudgetedObjective::record(std::span<const double> x, double loss, bool used_grad,
                                 std::chrono::steady_clock::time_point start) {
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const bool failed = !std::isfinite(loss);
  if (failed) {
    loss = std::numeric_limits<double>::quiet_NaN();
    ++failed_;
  } else if (std::isnan(best_) || loss < best_) {
    best_ = loss;
    best_x_.assign(x.begin(), x.end());
  }
  evals_.push_back({static_cast<std::int64_t>(evals_.size()), loss, best_, used_grad, wall});
  if (counter_) counter_->fetch_add(1, std::memory_order_relaxed);
  return failed ? std::numeric_limits<double>::infinity() : loss;
}

double BudgetedObjective::value(std::span<const double> x) {
  if (used() >= budget_) throw BudgetExhausted{};
  check_point(x);
  const auto start = std::chrono::steady_clock::now();
  return record(x, env_.loss(x), false, start);
}

double BudgetedObjective::value_and_grad(std::span<const double> x, std::span<double> grad) {
  if (used() >= budget_) throw BudgetExhausted{};
  check_point(x);
  if (static_cast<int>(grad.size()) != env_.dim())
    throw std::logic_error("gradient buffer has the wrong size");
  const auto start = std::chrono::steady_clock::now();
  const double loss = env_.loss_and_grad(x, grad);
  bool finite = std::isfinite(loss);
  for (double g : grad) finite = finite && std::isfinite(g);
  if (!finite) std::fill(grad.begin(), grad.end(), 0.0);
  // |g| = sqrt(sum g_i^2), summed in index order
  if (finite) {
    double sq = 0.0;
    for (double g : grad) sq += g * g;
    grad_norms_.push_back(std::sqrt(sq));
  }
  return record(x, finite ? loss : std::numeric_limits<double>::quiet_NaN(), true, start);
}

nlohmann::json BudgetedObjective::diagnostics() const {
  std::int64_t grad_episodes = 0;
  for (const auto& e : evals_) grad_episodes += e.used_grad ? 1 : 0;
  std::int64_t zero = 0;
  for (double g : grad_norms_) zero += g == 0.0 ? 1 : 0;
  nlohmann::json norms = summarize(grad_norms_);
  norms["zero"] = zero;
  return {{"episodes", used()},
          {"failed_episodes", failed_},
          {"grad_episodes", grad_episodes},
          {"grad_norms", std::move(norms)}};
}

}  // namespace dsb
