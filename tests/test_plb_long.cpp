// PlasticineLab tasks, the long checks (ctest label `long`, about 10 minutes): the loss measures
// the task (the reference motion far below zero actions and below 20 random action vectors, on
// every task), and the gradient over the whole 50-step horizon of one task against central
// differences.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/core/registry.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/plb_env.hpp"

namespace dsb {
namespace {

const mpm::PlbEnv& plb(const std::string& name) { return static_cast<const mpm::PlbEnv&>(*shared_env(name)); }

TEST(PlbLong, TheLossRanksTheReferenceMotionBelowZeroAndRandomActions) {
  for (const auto& t : mpm::plb_tasks()) {
    const auto& env = plb("plb-" + t.name);
    const auto& model = env.model();
    // the reference motion's per-env-step actions (its phases need not align with the segments)
    mpm::PlbLossScratch scratch(model.mpm);
    const mpm::PlbObjective objective(model, env.plb_config(), scratch);
    mpm::MpmWorkspace ws(model.mpm);
    const double reference = mpm::run_episode(model.mpm, ws, serial_team(), env.reference_actions(), 50, objective);
    const double zero = env.loss(std::vector<double>(env.dim(), 0.0));
    Rng rng(fnv1a64(t.name) ^ 20);
    double best_random = INFINITY;
    for (int r = 0; r < 20; ++r) {
      std::vector<double> x(env.dim());
      for (auto& v : x) v = rng.uniform(-1.0, 1.0);
      best_random = std::min(best_random, env.loss(x));
    }
    std::printf("  %-11s loss: reference %.2f, zero actions %.2f, best of 20 random %.2f\n", t.name.c_str(), reference,
                zero, best_random);
    EXPECT_LT(reference, 0.8 * zero) << t.name << ": far below doing nothing";
    EXPECT_LT(reference, best_random) << t.name;
  }
}

TEST(PlbLong, FullHorizonGradientMatchesCentralDifferences) {
  // pinch over all 50 env steps (950 substeps); the loss is ~100, so rounding noise in the
  // differences is ~1e-6: accept |analytic - central| <= 1e-5 + 1e-4 |central|
  const auto& env = plb("plb-pinch");
  GradientCheckOptions options;
  options.step = 1e-7;
  options.tolerance = 1e-4;
  options.absolute_floor = 1e-1;
  Rng rng(77);
  std::vector<double> x(env.dim());
  for (auto& v : x) v = rng.uniform(-1.0, 1.0);
  const auto r = check_gradient(env, x, options);
  std::printf("  pinch, 50 env steps: |grad| %.3e, worst absolute error %.2e, worst relative error %.2e\n",
              r.gradient_norm, r.worst_absolute_error, r.worst_relative_error);
  EXPECT_TRUE(r.value_agrees);
  EXPECT_TRUE(r.passed) << "worst coordinate " << r.worst_coordinate;
}

}  // namespace
}  // namespace dsb
