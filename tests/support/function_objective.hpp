#pragma once
// Test helper: a budgeted Objective over a plain function (and optional gradient), counting
// episodes and throwing BudgetExhausted exactly as the harness's budget wrapper does.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <span>
#include <stdexcept>
#include <vector>

#include "optimizers/core/objective.hpp"

namespace dsb::testing {

class FunctionObjective : public Objective {
 public:
  using Fn = std::function<double(std::span<const double>)>;
  using GradFn = std::function<double(std::span<const double>, std::span<double>)>;

  FunctionObjective(int dim, std::int64_t budget, Fn f, GradFn g = nullptr)
      : dim_(dim), budget_(budget), f_(std::move(f)), g_(std::move(g)) {}

  int dim() const override { return dim_; }
  bool has_gradient() const override { return static_cast<bool>(g_); }
  std::int64_t budget() const override { return budget_; }
  std::int64_t used() const override { return used_; }

  double value(std::span<const double> x) override {
    if (used_ >= budget_) throw BudgetExhausted{};
    return record(x, f_(x), false);
  }
  double value_and_grad(std::span<const double> x, std::span<double> grad) override {
    if (used_ >= budget_) throw BudgetExhausted{};
    if (!g_) throw std::logic_error("no gradient");
    return record(x, g_(x, grad), true);
  }

  double best() const { return best_; }
  const std::vector<double>& losses() const { return losses_; }
  const std::vector<std::vector<double>>& points() const { return points_; }
  int gradient_episodes() const { return grad_episodes_; }

 private:
  double record(std::span<const double> x, double loss, bool grad) {
    if (static_cast<int>(x.size()) != dim_) throw std::logic_error("wrong dimension");
    for (double xi : x)
      if (!(xi >= -1.0 && xi <= 1.0)) throw std::logic_error("point outside the box");
    ++used_;
    grad_episodes_ += grad ? 1 : 0;
    losses_.push_back(loss);
    points_.emplace_back(x.begin(), x.end());
    if (loss < best_) best_ = loss;
    return std::isfinite(loss) ? loss : std::numeric_limits<double>::infinity();
  }

  int dim_;
  std::int64_t budget_;
  Fn f_;
  GradFn g_;
  std::int64_t used_ = 0;
  int grad_episodes_ = 0;
  double best_ = std::numeric_limits<double>::infinity();
  std::vector<double> losses_;
  std::vector<std::vector<double>> points_;
};

// a flat landscape: loss 1 everywhere with a zero gradient (no step ever improves; for the
// optimizers' stall and restart rules)
inline FunctionObjective flat_objective(int dim, std::int64_t budget) {
  return FunctionObjective(
      dim, budget, [](std::span<const double>) { return 1.0; },
      [](std::span<const double>, std::span<double> g) {
        std::fill(g.begin(), g.end(), 0.0);
        return 1.0;
      });
}

}  // namespace dsb::testing
