// The budget wrapper and one run: counting, recording, best-so-far, failed episodes, rejection
// of points outside the box, and identical reruns.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "envs/core/registry.hpp"
#include "envs/synthetic/synthetic.hpp"
#include "harness/budget.hpp"
#include "harness/runner.hpp"
#include "optimizers/core/registry.hpp"

namespace dsb {
namespace {

// a 1-D env that blows up (NaN) for x > 0.5
class FragileEnv : public Env {
 public:
  const std::string& name() const override { return name_; }
  int dim() const override { return 1; }
  bool differentiable() const override { return true; }
  double loss(std::span<const double> x) const override {
    return x[0] > 0.5 ? std::numeric_limits<double>::quiet_NaN() : (x[0] - 0.2) * (x[0] - 0.2);
  }
  double loss_and_grad(std::span<const double> x, std::span<double> g) const override {
    g[0] = 2.0 * (x[0] - 0.2);
    return loss(x);
  }
  nlohmann::json config() const override { return {{"fragile", true}}; }

 private:
  std::string name_ = "fragile";
};

TEST(Budget, RecordsEveryEpisodeAndStopsAtTheBudget) {
  auto classic = *synthetic_config_from_name("sphere-3");
  classic.x_opt.assign(3, 0.0);  // unshifted: loss = 25 |x|^2
  const auto env = make_synthetic_env("sphere-3", classic);
  BudgetedObjective f(*env, 3);
  const std::vector<double> a{0.5, 0.0, 0.0}, b{0.1, 0.0, 0.0}, c{0.3, 0.0, 0.0};
  EXPECT_DOUBLE_EQ(f.value(a), 6.25);
  std::vector<double> g(3);
  EXPECT_DOUBLE_EQ(f.value_and_grad(b, g), 0.25);
  EXPECT_DOUBLE_EQ(f.value(c), 2.25);
  EXPECT_THROW(f.value(a), BudgetExhausted);
  ASSERT_EQ(f.evals().size(), 3u);
  EXPECT_EQ(f.evals()[1].episode, 1);
  EXPECT_TRUE(f.evals()[1].used_grad);
  EXPECT_FALSE(f.evals()[2].used_grad);
  EXPECT_DOUBLE_EQ(f.evals()[2].best_loss, 0.25);
  EXPECT_DOUBLE_EQ(f.best_loss(), 0.25);
  EXPECT_EQ(f.best_x(), b);
}

TEST(Budget, FailedEpisodeIsRecordedAsNaNAndNeverBest) {
  FragileEnv env;
  BudgetedObjective f(env, 4);
  const std::vector<double> bad{0.9}, good{0.0};
  EXPECT_EQ(f.value(bad), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(f.best_loss()));
  EXPECT_DOUBLE_EQ(f.value(good), 0.04);
  std::vector<double> g(1, 123.0);
  EXPECT_EQ(f.value_and_grad(bad, g), std::numeric_limits<double>::infinity());
  EXPECT_EQ(g[0], 0.0);
  EXPECT_EQ(f.failed_episodes(), 2);
  EXPECT_TRUE(std::isnan(f.evals()[0].loss));
  EXPECT_DOUBLE_EQ(f.evals()[2].best_loss, 0.04);
}

TEST(Budget, RejectsPointsOutsideTheBoxOrOfTheWrongSize) {
  const auto env = make_env("sphere-2");
  BudgetedObjective f(*env, 10);
  EXPECT_THROW(f.value(std::vector<double>{1.5, 0.0}), std::logic_error);
  EXPECT_THROW(f.value(std::vector<double>{std::nan(""), 0.0}), std::logic_error);
  EXPECT_THROW(f.value(std::vector<double>{0.0}), std::logic_error);
  EXPECT_EQ(f.used(), 0);
}

TEST(ExecuteRun, FullBudgetAndIdenticalReruns) {
  const auto env = make_env("cartpole3");
  RunSpec spec{"cartpole3", "cmaes", 0, 120, 77};
  auto opt1 = make_optimizer("cmaes"), opt2 = make_optimizer("cmaes");
  const RunResult a = execute_run(spec, *env, *opt1);
  const RunResult b = execute_run(spec, *env, *opt2);
  EXPECT_EQ(a.status, "done");
  EXPECT_EQ(a.episodes, 120);
  ASSERT_EQ(a.evals.size(), b.evals.size());
  for (std::size_t i = 0; i < a.evals.size(); ++i) EXPECT_EQ(a.evals[i].loss, b.evals[i].loss);
  EXPECT_EQ(a.best_x, b.best_x);
  EXPECT_EQ(a.best_loss, env->loss(a.best_x));
}

TEST(ExecuteRun, OptimizerErrorBecomesAFailedRun) {
  // gd on an env whose gradient call throws: recorded as failed with the message, no crash
  class Throwing : public FragileEnv {
    double loss_and_grad(std::span<const double>, std::span<double>) const override {
      throw std::runtime_error("solver diverged");
    }
  } env;
  auto gd = make_optimizer("gd");
  const RunResult r = execute_run({"fragile", "gd", 0, 10, 1}, env, *gd);
  EXPECT_EQ(r.status, "failed");
  EXPECT_NE(r.error.find("solver diverged"), std::string::npos);
}

}  // namespace
}  // namespace dsb
