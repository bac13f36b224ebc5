// Optimizer knobs (--set OPT.KEY=VALUE): parsing, the errors that name the bad knob or value,
// that a knob reaches the optimizer's behaviour, and that a knob at its default changes nothing.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/config_hash.hpp"
#include "common/error.hpp"
#include "optimizers/boleap.hpp"
#include "optimizers/gd.hpp"
#include "optimizers/registry.hpp"
#include "tests/support/function_objective.hpp"
#include "tests/support/test_functions.hpp"

namespace dsb {
namespace {

std::string error_of(const std::string& name, const KnobSettings& s) {
  try {
    make_optimizer(name, s);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

std::vector<std::vector<double>> points_of(const std::string& name, const KnobSettings& s, int dim,
                                           std::int64_t budget) {
  auto f = testing::shifted_sphere_objective(dim, budget, 0.3, 0.05);
  auto opt = make_optimizer(name, s);
  Rng rng(5);
  try {
    opt->minimize(f, rng);
  } catch (const BudgetExhausted&) {}
  return f.points();
}

TEST(KnobTable, SetsNumbersIntegersAndFlags) {
  double d = 1.0;
  int i = 3;
  bool b = true;
  KnobTable t("demo");
  t.add("d", &d).add("i", &i).add("b", &b);
  t.apply({{"d", "0.25"}, {"i", "-7"}, {"b", "false"}});
  EXPECT_EQ(d, 0.25);
  EXPECT_EQ(i, -7);
  EXPECT_FALSE(b);
  EXPECT_EQ(t.keys(), (std::vector<std::string>{"b", "d", "i"}));
}

TEST(KnobTable, ErrorsNameTheKnobAndTheValue) {
  EXPECT_EQ(error_of("boleap", {{"sigma", "1"}})
                .find("boleap: unknown knob 'sigma' (knobs: adam_per_leap, elite, episodes_per_leap, "
                      "leap_iterations, lr, max_descent_steps, patience, plain_steps, "
                      "population, sigma0, step_size)"),
            0u);
  EXPECT_NE(error_of("boleap", {{"patience", "2.5"}}).find("wants an integer, got '2.5'"), std::string::npos);
  EXPECT_NE(error_of("boleap", {{"sigma0", "nan"}}).find("wants a finite number, got 'nan'"), std::string::npos);
  EXPECT_NE(error_of("boleap", {{"sigma0", "0"}}).find("field 'sigma0'"), std::string::npos);
  EXPECT_NE(error_of("boleap", {{"elite", "11"}}).find("field 'elite'"), std::string::npos);
  EXPECT_NE(error_of("rand-descents", {{"start_scale", "1.5"}}).find("field 'start_scale'"), std::string::npos);
  EXPECT_NE(error_of("cmaes", {{"ipop", "maybe"}}).find("wants true or false, got 'maybe'"), std::string::npos);
  EXPECT_NE(error_of("ppo", {{"lr", "1"}}).find("optimizer 'ppo' has no knobs"), std::string::npos);
  // gd starts at the centre: it has no start_scale
  EXPECT_NE(error_of("gd", {{"start_scale", "0.5"}}).find("unknown knob 'start_scale'"), std::string::npos);
}

TEST(Knobs, ReachTheResolvedConfigAndItsHash) {
  const auto def = make_optimizer("boleap")->config();
  const auto same = make_optimizer("boleap", {{"sigma0", "0.3"}, {"elite", "5"}})->config();
  const auto other =
      make_optimizer("boleap", {{"sigma0", "0.3"}, {"max_descent_steps", "10"}, {"lr", "0.03"}})->config();
  EXPECT_EQ(config_hash(def), config_hash(same));  // elite 5 is K / 2 = the default
  EXPECT_NE(config_hash(def), config_hash(other));
  EXPECT_EQ(other["sigma0"].get<double>(), 0.3);
  EXPECT_EQ(other["max_descent_steps"].get<int>(), 10);
  EXPECT_EQ(def["max_descent_steps"].get<int>(), 30);
  EXPECT_EQ(other["adam"]["lr"].get<double>(), 0.03);
  EXPECT_EQ(def["elite"].get<int>(), 5);
}

TEST(Knobs, AKnobAtItsDefaultGivesTheSamePoints) {
  EXPECT_EQ(points_of("rand-descents", {}, 6, 300), points_of("rand-descents", {{"start_scale", "1"}}, 6, 300));
  EXPECT_EQ(points_of("boleap", {}, 3, 80), points_of("boleap", {{"elite", "5"}}, 3, 80));
}

TEST(Knobs, RandDescentsStartInsideStartScale) {
  // with max_steps 4 every 4th point starts a descent: uniform in [-0.1, 0.1]^d
  const auto pts = points_of("rand-descents", {{"start_scale", "0.1"}, {"max_steps", "4"}, {"patience", "0"}}, 5, 200);
  ASSERT_EQ(pts.size(), 200u);
  double widest = 0.0;
  for (std::size_t i = 0; i < pts.size(); i += 4)
    for (double xi : pts[i]) widest = std::max(widest, std::abs(xi));
  EXPECT_LE(widest, 0.1);
  EXPECT_GT(widest, 0.05);  // spread over the sub-box, not stuck at the centre
}

TEST(Knobs, BoLeapEliteAndDescentLengthChangeTheSearch) {
  // J = 1: every descent is one gradient step, so a leap of 40 episodes holds more populations
  BoLeapConfig cfg;
  cfg.max_descent_steps = 1;
  cfg.episodes_per_leap = 40;
  BoLeap one_step(cfg);
  auto f = testing::shifted_sphere_objective(3, 120, 0.3, 0.05);
  Rng rng(3);
  try {
    one_step.minimize(f, rng);
  } catch (const BudgetExhausted&) {}
  for (int len : one_step.last_run().descent_lengths) EXPECT_LE(len, 1);
  EXPECT_NE(points_of("boleap", {{"elite", "1"}}, 3, 80), points_of("boleap", {}, 3, 80));
}

}  // namespace
}  // namespace dsb
