#include "harness/budget.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/parallel.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

BudgetedObjective::BudgetedObjective(const Env& env, std::int64_t budget,
                                     std::atomic<std::int64_t>* episode_counter, ThreadTeam* team)
    : env_(env), budget_(budget), counter_(episode_counter), team_(team ? *team : serial_team()),
      workspaces_(static_cast<std::size_t>(team_.size())), best_(std::numeric_limits<double>::quiet_NaN()) {
  evals_.reserve(static_cast<std::size_t>(budget));
}

Workspace& BudgetedObjective::workspace(std::size_t slot) {
  if (!workspaces_[slot]) workspaces_[slot] = env_.make_workspace();
  return *workspaces_[slot];
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

double BudgetedObjective::record(std::span<const double> x, double loss, bool used_grad, double wall_s,
                                 double metric) {
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

double BudgetedObjective::value(std::span<const double> x) {
  if (used() >= budget_) throw BudgetExhausted{};
  check_point(x);
  const auto start = std::chrono::steady_clock::now();
  const double loss = env_.loss(x, workspace(0), team_);
  return record(x, loss, false, seconds_since(start), env_.episode_metric(workspace(0)));
}

double BudgetedObjective::value_and_grad(std::span<const double> x, std::span<double> grad) {
  if (used() >= budget_) throw BudgetExhausted{};
  check_point(x);
  if (static_cast<int>(grad.size()) != env_.dim())
    throw std::logic_error("gradient buffer has the wrong size");
  const auto start = std::chrono::steady_clock::now();
  const double loss = env_.loss_and_grad(x, grad, workspace(0), team_);
  bool finite = std::isfinite(loss);
  for (double g : grad) finite = finite && std::isfinite(g);
  if (!finite) std::fill(grad.begin(), grad.end(), 0.0);
  // |g| = sqrt(sum g_i^2), summed in index order
  if (finite) {
    double sq = 0.0;
    for (double g : grad) sq += g * g;
    grad_norms_.push_back(std::sqrt(sq));
  }
  return record(x, finite ? loss : std::numeric_limits<double>::quiet_NaN(), true, seconds_since(start),
                env_.episode_metric(workspace(0)));
}

void BudgetedObjective::values(std::span<const double> xs, std::span<double> out) {
  const std::size_t d = static_cast<std::size_t>(env_.dim());
  if (xs.size() != out.size() * d)
    throw std::logic_error("batch of " + std::to_string(out.size()) + " points has " +
                           std::to_string(xs.size()) + " values, expected " + std::to_string(out.size() * d));
  if (out.empty()) return;
  if (used() >= budget_) throw BudgetExhausted{};
  auto point = [&](std::size_t i) { return xs.subspan(i * d, d); };
  // what one-at-a-time evaluation would reach: the points before the first bad one, within budget
  std::size_t n = std::min<std::size_t>(out.size(), static_cast<std::size_t>(budget_ - used()));
  std::exception_ptr bad_point;
  for (std::size_t i = 0; i < n; ++i) {
    try {
      check_point(point(i));
    } catch (...) {
      bad_point = std::current_exception();
      n = i;
      break;
    }
  }
  // each slot takes every slots-th point with its own workspace, serially inside the rollout
  // (a nested parallel loop of the env runs on the slot's thread): results do not depend on the slot
  struct Outcome {
    double loss = 0.0, wall_s = 0.0, metric = 0.0;
    std::exception_ptr error;
  };
  std::vector<Outcome> outcomes(n);
  const std::size_t slots = std::min<std::size_t>(n, static_cast<std::size_t>(team_.size()));
  for (std::size_t s = 0; s < slots; ++s) workspace(s);
  team_.run(static_cast<int>(slots), [&](int slot) {
    for (std::size_t i = static_cast<std::size_t>(slot); i < n; i += slots) {
      const auto start = std::chrono::steady_clock::now();
      try {
        outcomes[i].loss = env_.loss(point(i), *workspaces_[slot], team_);
        outcomes[i].metric = env_.episode_metric(*workspaces_[slot]);
      } catch (...) {
        outcomes[i].error = std::current_exception();
      }
      outcomes[i].wall_s = seconds_since(start);
    }
  });
  for (std::size_t i = 0; i < n; ++i) {
    if (outcomes[i].error) std::rethrow_exception(outcomes[i].error);
    out[i] = record(point(i), outcomes[i].loss, false, outcomes[i].wall_s, outcomes[i].metric);
  }
  if (bad_point) std::rethrow_exception(bad_point);
  if (n < out.size()) throw BudgetExhausted{};
}

RlEnv& BudgetedObjective::rl_env() {
  if (!env_.supports_rl()) throw std::logic_error("env '" + env_.name() + "' has no RL view");
  if (!rl_) rl_ = env_.make_rl();
  return *rl_;
}

RlSpec BudgetedObjective::rl_spec() const {
  auto& self = const_cast<BudgetedObjective&>(*this);  // the view is made on first use
  const RlEnv& rl = self.rl_env();
  const int repeat = rl.action_repeat();
  return {rl.observation_dim(), rl.action_dim(), repeat, (rl.horizon() + repeat - 1) / repeat};
}

void BudgetedObjective::write_observation(std::span<double> observation) const {
  const std::vector<double> o = rl_->observe();
  if (observation.size() != o.size())
    throw std::logic_error("observation buffer has " + std::to_string(observation.size()) + " values, the env " +
                           std::to_string(o.size()));
  std::copy(o.begin(), o.end(), observation.begin());
}

void BudgetedObjective::rl_reset(std::span<double> observation) {
  RlEnv& rl = rl_env();
  if (rl_open_) throw std::logic_error("rl_reset while an episode is open: finish it first (it is recorded)");
  if (used() >= budget_) throw BudgetExhausted{};
  rl.reset();
  rl_open_ = true;
  rl_start_ = std::chrono::steady_clock::now();
  write_observation(observation);
}

RlStep BudgetedObjective::rl_step(std::span<const double> action, std::span<double> observation) {
  RlEnv& rl = rl_env();
  if (!rl_open_) throw std::logic_error("rl_step without an open episode (call rl_reset first)");
  if (static_cast<int>(action.size()) != rl.action_dim())
    throw std::logic_error("optimizer gave an action of size " + std::to_string(action.size()) + " on env '" +
                           env_.name() + "' with " + std::to_string(rl.action_dim()) + " actions");
  for (std::size_t i = 0; i < action.size(); ++i)
    if (!(action[i] >= -1.0 && action[i] <= 1.0))
      throw std::logic_error("optimizer gave action[" + std::to_string(i) + "] = " + std::to_string(action[i]) +
                             " outside [-1, 1]");
  // one decision: the action held for action_repeat env steps, or until the episode ends
  for (int k = 0; k < rl.action_repeat() && !rl.done(); ++k) rl.step(action);
  write_observation(observation);
  // a simulation that blew up (a non-finite observation) ends its episode as a failed one: the
  // optimizer never sees NaN, and nothing after the blow-up is simulated
  bool blown_up = false;
  for (const double o : observation) blown_up = blown_up || !std::isfinite(o);
  if (blown_up) std::fill(observation.begin(), observation.end(), 0.0);
  if (!rl.done() && !blown_up) return {false, 0.0};
  rl_open_ = false;
  const double loss = record({}, blown_up ? std::numeric_limits<double>::quiet_NaN() : rl.final_loss(), false,
                             seconds_since(rl_start_), std::numeric_limits<double>::quiet_NaN());
  return {true, loss};
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
