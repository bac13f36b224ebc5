// random, gd, rand-descents: descent behaviour on functions with known minima (the contract every
// optimizer keeps: test_optimizer_contract.cpp).
#include <cmath>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "optimizers/core/adam.hpp"
#include "optimizers/gd.hpp"
#include "optimizers/registry.hpp"
#include "tests/support/function_objective.hpp"
#include "tests/support/test_functions.hpp"

namespace dsb {
namespace {

using testing::flat_objective;
using testing::FunctionObjective;

// minimum 0 at c_i = 0.3 - 0.05 i
double shifted_sphere(std::span<const double> x, std::span<double> g = {}) {
  return testing::shifted_sphere(x, g, 0.3, 0.05);
}

FunctionObjective sphere_objective(int dim, std::int64_t budget) {
  return testing::shifted_sphere_objective(dim, budget, 0.3, 0.05);
}

std::vector<double> run(const std::string& name, FunctionObjective& f, std::uint64_t seed) {
  auto opt = make_optimizer(name);
  Rng rng(seed);
  try {
    opt->minimize(f, rng);
  } catch (const BudgetExhausted&) {}
  return f.losses();
}

// budget, box, seeds, hostile losses and resume: the contract of every optimizer
// (test_optimizer_contract.cpp); here, that the simple ones descend
class Descends : public ::testing::TestWithParam<std::string> {};

TEST_P(Descends, BelowHalfTheStartingLoss) {
  auto f = sphere_objective(6, 400);
  const auto losses = run(GetParam(), f, 2);
  EXPECT_LT(f.best(), 0.5 * losses.front()) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Optimizers, Descends, ::testing::Values("random", "gd", "rand-descents", "cmaes"));

TEST(Random, DifferentSeedsDifferentPointsUniformMean) {
  auto a = sphere_objective(3, 3000), b = sphere_objective(3, 100);
  run("random", a, 1);
  run("random", b, 2);
  EXPECT_NE(a.points()[0], b.points()[0]);
  double mean = 0.0;
  for (const auto& p : a.points()) mean += p[0];
  mean /= static_cast<double>(a.points().size());
  EXPECT_NEAR(mean, 0.0, 0.05);  // 3 standard errors of U(-1,1) over 3000 draws
}

TEST(Gd, StartsAtTheCentreAndConvergesToTheMinimum) {
  auto f = sphere_objective(4, 300);
  run("gd", f, 0);
  for (double xi : f.points().front()) EXPECT_EQ(xi, 0.0);
  EXPECT_EQ(f.gradient_episodes(), 300);
  EXPECT_LT(f.best(), 1e-6);
}

TEST(Gd, FirstAdamStepHasLengthLrPerCoordinate) {
  // Adam's bias-corrected first step is lr * g / (|g| + eps), i.e. lr * sign(g) up to eps/|g|
  auto f = sphere_objective(3, 2);
  run("gd", f, 0);
  const auto& x1 = f.points()[1];
  EXPECT_NEAR(x1[0], 0.1, 1e-7);  // c_0 = 0.3 > 0: gradient negative, step +lr
  EXPECT_NEAR(x1[1], 0.1, 1e-7);
  EXPECT_NEAR(x1[2], 0.1, 1e-7);
}

TEST(Gd, RecoversFromAFailedEpisode) {
  // losses are +inf beyond x_0 > 0.25: gd must back off and still finish the budget
  FunctionObjective f(
      2, 200, [](std::span<const double> x) { return shifted_sphere(x); },
      [](std::span<const double> x, std::span<double> g) {
        const double v = shifted_sphere(x, g);
        return x[0] > 0.25 ? std::numeric_limits<double>::quiet_NaN() : v;
      });
  run("gd", f, 0);
  EXPECT_EQ(f.used(), 200);
  EXPECT_LT(f.best(), 0.01);
}

TEST(RandDescents, RestartsFromRandomStartsAndStopsStaleDescents) {
  // constant function: every descent goes stale after `patience` steps and restarts
  FunctionObjective f = flat_objective(3, 100);
  run("rand-descents", f, 4);
  const int patience = rand_descents_defaults().patience;
  // the descent runs patience + 1 episodes (the first sets the best), then restarts elsewhere
  ASSERT_GT(f.used(), patience + 1);
  EXPECT_EQ(f.points()[0], f.points()[patience]);
  EXPECT_NE(f.points()[0], f.points()[patience + 1]);
}

TEST(RandDescents, DescentsAreCutAtExactlyMaxSteps) {
  // patience larger than max_steps and a step too small to reach the minimum: every descent
  // keeps improving, so only the max_steps cap can end it
  DescentConfig cfg = rand_descents_defaults();
  cfg.max_steps = 7;
  cfg.patience = 50;
  cfg.adam.lr = 0.01;
  auto f = sphere_objective(2, 70);
  auto opt = make_rand_descents(cfg);
  Rng rng(5);
  EXPECT_THROW(opt->minimize(f, rng), BudgetExhausted);
  ASSERT_EQ(f.points().size(), 70u);
  // the starts are the optimizer's only random draws: descent k starts at the k-th one
  Rng starts(5);
  for (int k = 0; k < 10; ++k) {
    std::vector<double> start(2);
    for (auto& xi : start) xi = starts.uniform(-1.0, 1.0);
    EXPECT_EQ(f.points()[7 * k], start) << "descent " << k << " does not start at episode " << 7 * k;
    for (int j = 1; j < 7; ++j)  // inside a descent: Adam steps, each one improving
      EXPECT_LT(f.losses()[7 * k + j], f.losses()[7 * k + j - 1]) << "descent " << k << " step " << j;
  }
}

TEST(OptimizerConfig, ValidationNamesTheField) {
  DescentConfig cfg = gd_defaults();
  cfg.adam.lr = -1.0;
  try {
    make_gd(cfg);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("'lr'"), std::string::npos) << e.what();
  }
}

TEST(OptimizerRegistry, UnknownNameIsAUsageErrorNamingIt) {
  try {
    make_optimizer("adamw");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("'adamw'"), std::string::npos);
  }
}

}  // namespace
}  // namespace dsb
