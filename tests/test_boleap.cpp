// `boleap` mechanics: every simulated point reaches the GP, the paper's stagnation stop, the
// per-leap episode cap, the knobs for what the paper leaves open (leap length in local iterations,
// plain clipped gradient steps, Adam's state per leap, the ablation without samples), exact budget
// use, determinism, refusal without gradients, and the CMA-ES update driven by the descent's end.
#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "optimizers/boleap.hpp"
#include "optimizers/cmaes.hpp"
#include "tests/support/function_objective.hpp"
#include "tests/support/test_functions.hpp"

namespace dsb {
namespace {

using testing::flat_objective;
using testing::FunctionObjective;

// shifted sphere with gradient, minimum 0 at c_i = 0.4 - 0.1 i
FunctionObjective bowl_objective(int dim, std::int64_t budget) {
  return testing::shifted_sphere_objective(dim, budget, 0.4, 0.1);
}

BoLeapStats run(FunctionObjective& f, std::uint64_t seed, BoLeapConfig cfg = {}) {
  BoLeap opt(cfg);
  Rng rng(seed);
  EXPECT_THROW(opt.minimize(f, rng), BudgetExhausted);
  return opt.last_run();
}

TEST(BoLeap, UsesExactlyTheBudgetAndEveryPointReachesTheGp) {
  auto f = bowl_objective(3, 437);
  const BoLeapStats s = run(f, 1);
  EXPECT_EQ(f.used(), 437);
  // the refused request after the budget is counted by the optimizer, not by the objective
  EXPECT_EQ(s.episodes_seen, 438);
  // the GP at the last BO proposal held every point simulated before it: the initial design and
  // all complete leaps (samples and descent iterates)
  const int n_init = BoConfig{}.initial_points_for(3);
  const int before_last = std::accumulate(s.leap_episodes.begin(), s.leap_episodes.end() - 1, 0);
  EXPECT_EQ(s.gp_points, n_init + before_last);
  EXPECT_GE(s.leaps, 4);
  // gradients were used: every descent step is a gradient episode
  EXPECT_EQ(f.gradient_episodes(), std::accumulate(s.descent_lengths.begin(), s.descent_lengths.end(), 0));
}

TEST(BoLeap, LeapsRespectTheEpisodeCap) {
  auto f = bowl_objective(4, 900);
  BoLeapConfig cfg;
  const BoLeapStats s = run(f, 2, cfg);
  const int room = cfg.population + cfg.max_descent_steps;
  for (std::size_t i = 0; i + 1 < s.leap_episodes.size(); ++i) {
    EXPECT_LE(s.leap_episodes[i], cfg.episodes_per_leap);
    // a leap ends only when no further local step fits, or when CMA-ES's stop tests fire
    EXPECT_GE(s.leap_episodes[i], cfg.population + 1);
    (void)room;
  }
}

TEST(BoLeap, DescentStopsAfterMoreThanThreeNonImprovingSteps) {
  // constant loss: the first step sets the best, the next four fail to improve: the paper halts a
  // descent when the loss "stagnates or increases for more than three steps" -> 5 steps
  FunctionObjective f = flat_objective(2, 300);
  const BoLeapStats s = run(f, 3);
  ASSERT_GE(s.descent_lengths.size(), 3u);
  for (std::size_t i = 0; i + 1 < s.descent_lengths.size(); ++i) {
    EXPECT_EQ(s.descent_lengths[i], 5);
    EXPECT_EQ(s.stale_stops[i], 1);
  }
}

TEST(BoLeap, TheKnobsForWhatThePaperLeavesOpen) {
  // leap length in local iterations: 2 iterations of K samples and one descent each per leap
  {
    auto f = bowl_objective(3, 400);
    BoLeapConfig cfg;
    cfg.leap_iterations = 2;
    const BoLeapStats s = run(f, 1, cfg);
    for (std::size_t i = 0; i + 1 < s.leap_episodes.size(); ++i) {
      int descents = 0, steps = 0;
      for (std::size_t k = 0; k < s.descent_leap.size(); ++k)
        if (s.descent_leap[k] == static_cast<int>(i)) ++descents, steps += s.descent_lengths[k];
      if (s.leap_stops[i] != CmaStop::none) continue;  // a leap CMA-ES ended early
      EXPECT_EQ(descents, 2) << i;
      EXPECT_EQ(s.leap_episodes[i], 2 * cfg.population + steps) << i;
    }
  }
  // plain clipped gradient steps: x <- clip(x - alpha g); on f = |x|^2 / 2 from the descent's
  // start the second iterate is (1 - alpha) times the first
  {
    std::vector<std::vector<double>> seen;
    FunctionObjective f(
        2, 60, [](std::span<const double> x) { return 0.5 * (x[0] * x[0] + x[1] * x[1]); },
        [&](std::span<const double> x, std::span<double> g) {
          seen.emplace_back(x.begin(), x.end());
          g[0] = x[0];
          g[1] = x[1];
          return 0.5 * (x[0] * x[0] + x[1] * x[1]);
        });
    BoLeapConfig cfg;
    cfg.plain_steps = true;
    cfg.step_size = 0.25;
    run(f, 2, cfg);
    ASSERT_GE(seen.size(), 2u);
    EXPECT_DOUBLE_EQ(seen[1][0], 0.75 * seen[0][0]);
    EXPECT_DOUBLE_EQ(seen[1][1], 0.75 * seen[0][1]);
  }
  // the ablation: population 1, every leap one descent from BO's proposal, no samples
  {
    auto f = bowl_objective(3, 300);
    BoLeapConfig cfg;
    cfg.population = 1;
    const BoLeapStats s = run(f, 4, cfg);
    EXPECT_EQ(static_cast<int>(s.descent_lengths.size()), s.leaps);
    EXPECT_EQ(f.gradient_episodes(), f.used() - cfg.bo.initial_points_for(3));
  }
  // Adam's state across one leap's descents changes the trajectory (same seed)
  {
    auto a = bowl_objective(3, 300), b = bowl_objective(3, 300);
    BoLeapConfig per_leap;
    per_leap.adam_per_leap = true;
    run(a, 5);
    run(b, 5, per_leap);
    EXPECT_NE(a.losses(), b.losses());
  }
}

TEST(BoLeap, DescentRunsJStepsWhileItImproves) {
  auto f = bowl_objective(2, 200);
  BoLeapConfig cfg;
  cfg.adam.lr = 0.01;  // small steps on a bowl keep improving for 10 of them (19 from this start)
  cfg.max_descent_steps = 10;
  const BoLeapStats s = run(f, 4, cfg);
  ASSERT_FALSE(s.descent_lengths.empty());
  EXPECT_EQ(s.descent_lengths.front(), cfg.max_descent_steps);
  EXPECT_EQ(s.stale_stops.front(), 0);
}

TEST(BoLeap, SameSeedBitIdenticalDifferentSeedDifferent) {
  auto a = bowl_objective(3, 250), b = bowl_objective(3, 250), c = bowl_objective(3, 250);
  run(a, 7);
  run(b, 7);
  run(c, 8);
  EXPECT_EQ(a.losses(), b.losses());
  EXPECT_NE(a.losses(), c.losses());
}

TEST(BoLeap, FindsTheBowlMinimum) {
  // random search gets about 0.1 here with 400 samples; Adam's descents (lr 0.03, up to J = 30
  // steps) resolve the bowl to the scale of their step and the shrinking CMA-ES population refines
  // below that
  auto f = bowl_objective(5, 400);
  run(f, 5);
  EXPECT_LT(f.best(), 1e-2);
}

TEST(BoLeap, RefusesAnObjectiveWithoutGradients) {
  FunctionObjective f(2, 10, [](std::span<const double> x) { return x[0] * x[0]; });
  BoLeap opt;
  Rng rng(1);
  try {
    opt.minimize(f, rng);
    FAIL() << "boleap ran without gradients";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("gradient"), std::string::npos);
  }
  EXPECT_EQ(f.used(), 0);
}

TEST(BoLeapCma, MovedMeanDrivesThePathsAndTheMean) {
  // tell with a moved mean: the mean lands exactly there and p_sigma follows the realized step
  CmaesConfig cfg;
  Eigen::VectorXd m0 = Eigen::VectorXd::Zero(3);
  CmaState a(m0, 0.5, 10, cfg), b(m0, 0.5, 10, cfg);
  Rng ra(1), rb(1);
  std::vector<Eigen::VectorXd> xs;
  std::vector<double> fs;
  for (int k = 0; k < 10; ++k) {
    xs.push_back(a.ask(ra));
    b.ask(rb);
    fs.push_back(xs.back().squaredNorm());
  }
  Eigen::VectorXd moved(3);
  moved << 0.3, -0.2, 0.1;
  a.tell(xs, fs, &moved);
  b.tell(xs, fs);
  EXPECT_EQ(a.mean(), moved);
  EXPECT_NE(b.mean(), moved);
  // first generation: p_sigma = sqrt(cs (2 - cs) mu_eff) C^-1/2 y_w with C = I, y_w = moved / sigma0
  const auto& k = a.constants();
  const Eigen::VectorXd expected = std::sqrt(k.c_sigma * (2.0 - k.c_sigma) * k.mu_eff) * moved / 0.5;
  EXPECT_NEAR((a.p_sigma() - expected).norm(), 0.0, 1e-12);
}

TEST(BoLeapConfigTest, ValidationNamesTheField) {
  BoLeapConfig cfg;
  cfg.population = 0;
  try {
    BoLeap opt(cfg);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("population"), std::string::npos) << e.what();
  }
  cfg = {};
  cfg.step_size = -0.1;
  EXPECT_THROW(BoLeap{cfg}, ConfigError);
  cfg = {};
  cfg.leap_iterations = -1;
  EXPECT_THROW(BoLeap{cfg}, ConfigError);
}

}  // namespace
}  // namespace dsb
