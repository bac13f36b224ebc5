// The gradient checker (envs/core/gradient_check.hpp): a correct gradient passes with small
// errors, a gradient wrong in one coordinate fails naming it, loss() and loss_and_grad() must
// agree on the value, the finite differences go only through loss() and stay inside the box, a
// step function counts as exactly zero, the survey's statistics on sphere match closed forms,
// the large-step check along the gradient (exact on a quadratic, opposed on every point of a
// sawtooth whose every ramp rises, no direction where the gradient is zero, its window shifted
// inside the box), options name the bad field, and `harness gradcheck --json` prints the fields.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/registry.hpp"
#include "envs/synthetic/synthetic.hpp"
#include "support/config_error.hpp"

namespace dsb {
namespace {

// A test env from two functions: the value-only path and the value-and-gradient path. Counts the
// calls of each and records every x the value path sees.
class FunctionEnv final : public Env {
 public:
  using Value = std::function<double(std::span<const double>)>;
  using ValueAndGrad = std::function<double(std::span<const double>, std::span<double>)>;
  FunctionEnv(int dim, Value value, ValueAndGrad value_and_grad)
      : Env(EnvInfo{"test-function", dim, static_cast<bool>(value_and_grad), false, false, 0.0, ""}),
        dim_(dim),
        value_(std::move(value)),
        value_and_grad_(std::move(value_and_grad)) {}

  nlohmann::json config() const override { return {{"dim", dim_}}; }

 protected:
  double rollout(std::span<const double> x, Workspace&, ThreadTeam&) const override {
    ++value_calls;
    seen.emplace_back(x.begin(), x.end());
    return value_(x);
  }
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override {
    if (!value_and_grad_) return Env::rollout_with_grad(x, grad, ws, team);
    ++gradient_calls;
    return value_and_grad_(x, grad);
  }

 public:
  mutable int value_calls = 0, gradient_calls = 0;
  mutable std::vector<std::vector<double>> seen;

 private:
  int dim_;
  Value value_;
  ValueAndGrad value_and_grad_;
};

// f = sum_i (i + 1) x_i^2 + sin(x_0) x_1, with gradient; `wrong` scales coordinate 2's by 1.01
double smooth(std::span<const double> x, std::span<double> g, bool wrong = false) {
  double f = std::sin(x[0]) * x[1];
  for (std::size_t i = 0; i < x.size(); ++i) f += static_cast<double>(i + 1) * x[i] * x[i];
  if (!g.empty()) {
    for (std::size_t i = 0; i < x.size(); ++i) g[i] = 2.0 * static_cast<double>(i + 1) * x[i];
    g[0] += std::cos(x[0]) * x[1];
    g[1] += std::sin(x[0]);
    if (wrong) g[2] *= 1.01;
  }
  return f;
}

FunctionEnv smooth_env(bool wrong = false) {
  return FunctionEnv(
      4, [](std::span<const double> x) { return smooth(x, {}); },
      [wrong](std::span<const double> x, std::span<double> g) { return smooth(x, g, wrong); });
}

TEST(GradientCheck, CorrectGradientPassesWithSmallErrors) {
  const auto env = smooth_env();
  const std::vector<double> x = {0.3, -0.7, 0.2, 0.55};
  const auto r = check_gradient(env, x);
  EXPECT_TRUE(r.passed);
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.value_agrees);
  EXPECT_TRUE(r.gradient_agrees);
  EXPECT_FALSE(r.exactly_zero);
  EXPECT_FALSE(r.bit_equal_to_differences);
  EXPECT_EQ(r.loss, smooth(x, {}));
  EXPECT_EQ(r.value_path_loss, r.loss);
  std::vector<double> g(4);
  smooth(x, g);
  ASSERT_EQ(r.coordinates.size(), 4u);
  double norm2 = 0.0;
  for (int i = 0; i < 4; ++i) {
    const auto& c = r.coordinates[i];
    EXPECT_EQ(c.analytic, g[i]);
    // central differences with h = 1e-6: truncation h^2 |f'''| / 6 plus rounding eps |f| / h
    EXPECT_NEAR(c.differences.central, g[i], 1e-8) << "coordinate " << i;
    EXPECT_NEAR(c.differences.right, g[i], 1e-5) << "coordinate " << i;  // first order: h |f''| / 2
    EXPECT_NEAR(c.differences.left, g[i], 1e-5) << "coordinate " << i;
    EXPECT_EQ(c.absolute_error, std::abs(c.analytic - c.differences.central));
    EXPECT_LT(c.relative_error, 1e-8);
    EXPECT_TRUE(c.agrees);
    norm2 += g[i] * g[i];
  }
  EXPECT_DOUBLE_EQ(r.gradient_norm, std::sqrt(norm2));
  EXPECT_LT(r.worst_relative_error, 1e-8);
  EXPECT_GE(r.worst_coordinate, 0);
  EXPECT_EQ(r.worst_relative_error, r.coordinates[r.worst_coordinate].relative_error);
}

TEST(GradientCheck, AlongChosenCoordinatesAndDirectionCosine) {
  const std::vector<double> x = {0.3, -0.7, 0.2, 0.55};
  // only coordinates 2 and 0, in that order; the wrong coordinate 2 is named by its env index
  const auto env = smooth_env(/*wrong=*/true);
  const auto ws = env.make_workspace();
  const std::vector<int> coords = {2, 0};
  const auto r = check_gradient_along(env, *ws, x, coords, {});
  ASSERT_EQ(r.coordinates.size(), 2u);
  std::vector<double> g(4);
  smooth(x, g, true);
  EXPECT_EQ(r.coordinates[0].analytic, g[2]);
  EXPECT_EQ(r.coordinates[1].analytic, g[0]);
  EXPECT_EQ(r.worst_coordinate, 2);
  EXPECT_FALSE(r.coordinates[0].agrees);
  EXPECT_TRUE(r.coordinates[1].agrees);
  // cos between (1.01 g2, g0) and (g2, g0): closed form, to the differences' accuracy
  const double a0 = g[2] / 1.01, a1 = g[0];  // the exact gradient's components (g[2] was scaled by 1.01)
  const double cos = (1.01 * a0 * a0 + a1 * a1) / (std::hypot(1.01 * a0, a1) * std::hypot(a0, a1));
  EXPECT_NEAR(r.direction_cosine, cos, 1e-9);
  EXPECT_LT(r.direction_cosine, 1.0 - 1e-7);  // the 1% error tilts it by 5.7e-4 rad: 1 - cos = 1.6e-7

  // a correct gradient points the differences' way (cos 1), its negative the opposite way (-1)
  EXPECT_NEAR(check_gradient(smooth_env(), x).direction_cosine, 1.0, 1e-12);
  FunctionEnv negated(
      4, [](std::span<const double> y) { return smooth(y, {}); },
      [](std::span<const double> y, std::span<double> gy) {
        const double f = smooth(y, gy);
        for (double& v : gy) v = -v;
        return f;
      });
  EXPECT_NEAR(check_gradient(negated, x).direction_cosine, -1.0, 1e-12);
  GradientSurveyOptions o;
  o.points = 6;
  o.seed = 4;
  const auto good = survey_gradient(smooth_env(), o);
  EXPECT_EQ(good.directed, 6);
  EXPECT_EQ(good.aligned, 6);
  EXPECT_EQ(good.opposed, 0);
  const auto bad = survey_gradient(negated, o);
  EXPECT_EQ(bad.directed, 6);
  EXPECT_EQ(bad.aligned, 0);
  EXPECT_EQ(bad.opposed, 6);
}

TEST(GradientCheck, WrongCoordinateFailsAndIsNamed) {
  const auto env = smooth_env(/*wrong=*/true);
  const std::vector<double> x = {0.3, -0.7, 0.2, 0.55};
  const auto r = check_gradient(env, x);
  EXPECT_FALSE(r.passed);
  EXPECT_FALSE(r.gradient_agrees);
  EXPECT_TRUE(r.value_agrees);
  EXPECT_EQ(r.worst_coordinate, 2);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r.coordinates[i].agrees, i != 2) << "coordinate " << i;
  // coordinate 2: analytic 1.01 g, central ~ g = 6 x_2 = 1.2; max |central| is coordinate 3's
  // 8 x_3 = 4.4, so the relative error is 0.01 g / (|g| + 1e-3 * 4.4)
  const double g2 = 6.0 * 0.2, scale = 8.0 * 0.55;
  EXPECT_NEAR(r.worst_relative_error, 0.01 * g2 / (g2 + 1e-3 * scale), 1e-7);
  EXPECT_NEAR(r.worst_absolute_error, 0.01 * g2, 1e-8);

  // over random points too: every point fails in coordinate 2
  GradientSurveyOptions o;
  o.points = 10;
  o.seed = 3;
  const auto s = survey_gradient(env, o);
  EXPECT_FALSE(s.passed);
  EXPECT_EQ(s.agreeing, 0);
  EXPECT_EQ(s.worst_coordinate, 2);
  for (const auto& c : s.checks) EXPECT_EQ(c.worst_coordinate, 2);
}

TEST(GradientCheck, LossAndLossAndGradMustAgreeOnTheValue) {
  // the gradient path's loss is one ulp above the value path's
  FunctionEnv env(
      4, [](std::span<const double> x) { return smooth(x, {}); },
      [](std::span<const double> x, std::span<double> g) {
        return std::nextafter(smooth(x, g), std::numeric_limits<double>::infinity());
      });
  const std::vector<double> x = {0.3, -0.7, 0.2, 0.55};
  const auto r = check_gradient(env, x);
  EXPECT_FALSE(r.value_agrees);
  EXPECT_TRUE(r.gradient_agrees);
  EXPECT_FALSE(r.passed);
  GradientCheckOptions lenient;
  lenient.value_tolerance = 1e-12;
  EXPECT_TRUE(check_gradient(env, x, lenient).passed);
}

TEST(GradientCheck, DifferencesGoOnlyThroughLossAndStayInTheBox) {
  const auto env = smooth_env();
  const std::vector<double> x = {1.0, -1.0, -1.0 + 2e-7, 0.0};
  const double h = 1e-6;
  GradientCheckOptions o;
  o.step = h;
  const auto r = check_gradient(env, x, o);
  EXPECT_EQ(env.gradient_calls, 1);
  EXPECT_EQ(env.value_calls, 2 * 4 + 1);
  for (const auto& y : env.seen)
    for (double v : y) {
      EXPECT_GE(v, -1.0);
      EXPECT_LE(v, 1.0);
    }
  // at the upper edge the window is [1 - 2h, 1]: a one-sided difference, no room on the right
  const auto& c0 = r.coordinates[0].differences;
  EXPECT_TRUE(std::isnan(c0.right));
  EXPECT_EQ(c0.left, c0.central);
  // f along x_0 near 1: sin(x_0) x_1 + x_0^2 with x_1 = -1; backward difference error h |f''|
  EXPECT_NEAR(c0.central, -std::cos(1.0) + 2.0, 2.0 * h * 3.0);
  // at the lower edge [-1, -1 + 2h]; the window keeps its width where x is inside it
  EXPECT_TRUE(std::isnan(r.coordinates[1].differences.left));
  EXPECT_FALSE(std::isnan(r.coordinates[2].differences.left));
  EXPECT_FALSE(std::isnan(r.coordinates[2].differences.right));
  EXPECT_NEAR(r.coordinates[2].differences.central, 6.0 * x[2], 2.0 * h * 3.0);
  EXPECT_TRUE(r.passed) << r.worst_relative_error;
}

// f = floor(4 x_0) + floor(4 x_1) with the gradient it has almost everywhere: 0
FunctionEnv step_function_env() {
  auto f = [](std::span<const double> x) { return std::floor(4.0 * x[0]) + std::floor(4.0 * x[1]); };
  return FunctionEnv(2, f, [f](std::span<const double> x, std::span<double> g) {
    g[0] = g[1] = 0.0;
    return f(x);
  });
}

// the survey of step_function_env at `points` points, the other options the defaults
GradientSurvey survey_step_function(int points) {
  GradientSurveyOptions o;
  o.points = points;
  return survey_gradient(step_function_env(), o);
}

TEST(GradientCheck, StepFunctionCountsAsExactlyZero) {
  // gradient 0 everywhere but on the steps
  const auto s = survey_step_function(50);
  EXPECT_EQ(s.exactly_zero, 50);
  EXPECT_EQ(s.agreeing, 50);  // no step within 1e-6 of any of these points
  EXPECT_EQ(s.non_finite, 0);
  EXPECT_EQ(s.gradient_norm.min, 0.0);
  EXPECT_EQ(s.gradient_norm.max, 0.0);
  EXPECT_TRUE(s.passed);
  // on a step the difference sees the jump: 1 / 2h, and the exactly-zero gradient disagrees
  const FunctionEnv env = step_function_env();
  const auto r = check_gradient(env, std::vector<double>{0.25, 0.1});
  EXPECT_TRUE(r.exactly_zero);
  EXPECT_FALSE(r.passed);
  EXPECT_EQ(r.worst_coordinate, 0);
  EXPECT_NEAR(r.coordinates[0].differences.central, 1.0 / 2e-6, 1e-3);
}

TEST(GradientCheck, GradientMadeOfTheSameDifferencesIsFlagged) {
  // a "gradient" that is the checker's own central difference of loss()
  auto f = [](std::span<const double> x) { return std::exp(x[0]) * x[1] + x[1] * x[1]; };
  FunctionEnv env(2, f, [f](std::span<const double> x, std::span<double> g) {
    for (int i = 0; i < 2; ++i) {
      std::vector<double> hi(x.begin(), x.end()), lo(x.begin(), x.end());
      hi[i] += 1e-6;
      lo[i] -= 1e-6;
      g[i] = (f(hi) - f(lo)) / (hi[i] - lo[i]);
    }
    return f(x);
  });
  const auto r = check_gradient(env, std::vector<double>{0.2, 0.4});
  EXPECT_TRUE(r.bit_equal_to_differences);
  EXPECT_TRUE(r.passed);  // a flag, not a failure
  EXPECT_FALSE(check_gradient(smooth_env(), std::vector<double>{0.2, 0.4, 0.1, 0.0}).bit_equal_to_differences);
}

TEST(GradientCheck, BlownUpSimulationIsNonFinite) {
  auto f = [](std::span<const double> x) { return x[0] > 0.0 ? std::numeric_limits<double>::quiet_NaN() : x[0]; };
  FunctionEnv env(1, f, [f](std::span<const double> x, std::span<double> g) {
    g[0] = x[0] > 0.0 ? std::numeric_limits<double>::quiet_NaN() : 1.0;
    return f(x);
  });
  const auto r = check_gradient(env, std::vector<double>{0.5});
  EXPECT_FALSE(r.finite);
  EXPECT_TRUE(r.value_agrees);  // the same blow-up on both paths
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(std::isnan(r.worst_relative_error));
  EXPECT_EQ(r.worst_coordinate, 0);
  GradientSurveyOptions o;
  o.points = 20;
  const auto s = survey_gradient(env, o);
  EXPECT_GT(s.non_finite, 0);
  EXPECT_LT(s.non_finite, 20);
  EXPECT_EQ(s.agreeing, 20 - s.non_finite);
  EXPECT_FALSE(s.passed);
  EXPECT_TRUE(std::isnan(s.worst_relative_error));
  EXPECT_TRUE(std::isnan(s.checks[s.worst_point].worst_relative_error));
}

TEST(GradientCheck, QuartilesInterpolateBetweenOrderStatistics) {
  const auto q = quartiles({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(q.min, 1.0);
  EXPECT_EQ(q.q1, 1.75);
  EXPECT_EQ(q.median, 2.5);
  EXPECT_EQ(q.q3, 3.25);
  EXPECT_EQ(q.max, 4.0);
  const auto one = quartiles({5.0});
  EXPECT_EQ(one.q1, 5.0);
  EXPECT_EQ(one.q3, 5.0);
  EXPECT_TRUE(std::isnan(quartiles({}).median));
}

// sphere-D: f = sum (z_i - z*_i)^2 with z = centre + halfwidth x, so df/dx_i = 2 (z_i - z*_i) halfwidth_i
TEST(GradientSurvey, SphereStatisticsMatchClosedForms) {
  const std::string name = "sphere-4";
  const auto env = make_env(name);
  const auto cfg = synthetic_config_from_name(name);
  const auto opt = synthetic_known_optimum(name);
  ASSERT_TRUE(cfg && opt);
  GradientSurveyOptions o;
  o.points = 5;  // quartiles fall on order statistics 1, 2, 3
  o.seed = 7;
  o.amplitude = 0.8;
  const auto s = survey_gradient(*env, o);
  Rng rng(7);
  std::vector<double> norms;
  for (int p = 0; p < 5; ++p) {
    double norm2 = 0.0;
    for (int i = 0; i < 4; ++i) {
      const double x = 0.8 * rng.uniform(-1.0, 1.0);
      EXPECT_EQ(s.x[p][i], x);
      const double centre = 0.5 * (cfg->lower[i] + cfg->upper[i]);
      const double halfwidth = 0.5 * (cfg->upper[i] - cfg->lower[i]);
      const double g = 2.0 * (centre + halfwidth * x - opt->x_physical[i]) * halfwidth;
      EXPECT_NEAR(s.checks[p].coordinates[i].analytic, g, 1e-12 * std::abs(g));
      norm2 += g * g;
    }
    norms.push_back(std::sqrt(norm2));
    EXPECT_NEAR(s.checks[p].gradient_norm, norms.back(), 1e-12 * norms.back());
  }
  std::sort(norms.begin(), norms.end());
  const double expected[5] = {norms[0], norms[1], norms[2], norms[3], norms[4]};
  const double got[5] = {s.gradient_norm.min, s.gradient_norm.q1, s.gradient_norm.median, s.gradient_norm.q3,
                         s.gradient_norm.max};
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(got[k], expected[k], 1e-12 * expected[k]) << "statistic " << k;
  EXPECT_EQ(s.points, 5);
  EXPECT_EQ(s.agreeing, 5);
  EXPECT_EQ(s.exactly_zero, 0);
  EXPECT_EQ(s.non_finite, 0);
  EXPECT_EQ(s.value_mismatches, 0);
  EXPECT_TRUE(s.passed);
  // a quadratic: central differences are exact but for rounding, eps |f| / h ~ 1e-9 relative
  EXPECT_LT(s.worst_relative_error, 1e-7);
}

// f = x - 0.2 floor(10 x): every ramp rises with slope 1, every 0.1 the loss drops by 0.2, so a
// window of width 2H = 0.1 always holds exactly one drop: (2H - 0.2) / 2H = -1 along +g
FunctionEnv sawtooth_env() {
  auto f = [](std::span<const double> x) { return x[0] - 0.2 * std::floor(10.0 * x[0]); };
  return FunctionEnv(1, f, [f](std::span<const double> x, std::span<double> g) {
    g[0] = 1.0;
    return f(x);
  });
}

TEST(LargeStep, SawtoothGradientAgreesLocallyAndIsOpposedOverTheStep) {
  GradientSurveyOptions o;
  o.points = 20;
  o.large_step = 0.05;
  const auto s = survey_gradient(sawtooth_env(), o);
  EXPECT_EQ(s.agreeing, 20);  // no drop within 1e-6 of these points
  EXPECT_EQ(s.exactly_zero, 0);
  ASSERT_EQ(s.large_steps.size(), 20u);
  EXPECT_EQ(s.large_step_directed, 20);
  EXPECT_EQ(s.large_step_opposed, 20);
  EXPECT_EQ(s.large_step_flat, 0);
  for (const auto& l : s.large_steps) {
    EXPECT_EQ(l.lo, -0.05);
    EXPECT_EQ(l.hi, 0.05);
    EXPECT_NEAR(l.ratio, -1.0, 1e-12);
  }
  EXPECT_NEAR(s.large_step_ratio.median, -1.0, 1e-12);
  EXPECT_TRUE(s.passed);  // the large-step check never fails a point
}

TEST(LargeStep, ExactOnAQuadraticAlongTheSphereGradient) {
  // a quadratic's central difference over [-H, H] is exact: the slope along u is g . u = |g|
  GradientSurveyOptions o;
  o.points = 10;
  o.seed = 3;
  o.large_step = 0.05;
  const auto s = survey_gradient(*make_env("sphere-4"), o);
  EXPECT_EQ(s.agreeing, 10);
  EXPECT_EQ(s.large_step_directed, 10);
  EXPECT_EQ(s.large_step_opposed, 0);
  for (const auto& l : s.large_steps) EXPECT_NEAR(l.ratio, 1.0, 1e-9);
  EXPECT_NEAR(s.large_step_ratio.min, 1.0, 1e-9);
  EXPECT_NEAR(s.large_step_ratio.max, 1.0, 1e-9);
  // off: no large-step checks
  o.large_step = 0.0;
  const auto off = survey_gradient(*make_env("sphere-4"), o);
  EXPECT_TRUE(off.large_steps.empty());
  EXPECT_EQ(off.large_step_directed, 0);
  EXPECT_EQ(off.agreeing, 10);
}

TEST(LargeStep, ZeroGradientHasNoDirection) {
  const auto s = survey_step_function(10);
  EXPECT_EQ(s.exactly_zero, 10);
  ASSERT_EQ(s.large_steps.size(), 10u);
  EXPECT_EQ(s.large_step_directed, 0);
  EXPECT_EQ(s.large_step_opposed, 0);
  EXPECT_TRUE(std::isnan(s.large_steps[0].ratio));
  EXPECT_TRUE(std::isnan(s.large_step_ratio.median));
}

TEST(LargeStep, WindowShiftsInsideTheBox) {
  // f = 3 x_0 - x_1: u = (3, -1) / sqrt(10); at x_0 = 0.99 the box allows t <= 0.01 sqrt(10) / 3
  auto f = [](std::span<const double> x) { return 3.0 * x[0] - x[1]; };
  FunctionEnv env(2, f, [f](std::span<const double> x, std::span<double> g) {
    g[0] = 3.0;
    g[1] = -1.0;
    return f(x);
  });
  const auto ws = env.make_workspace();
  const std::vector<double> grad{3.0, -1.0};
  const auto l = check_large_step(env, *ws, std::vector<double>{0.99, 0.0}, grad, 0.05);
  const double t_max = 0.01 * std::sqrt(10.0) / 3.0;
  EXPECT_NEAR(l.hi, t_max, 1e-15);
  EXPECT_NEAR(l.lo, t_max - 0.1, 1e-15);
  EXPECT_NEAR(l.ratio, 1.0, 1e-12);  // linear: exact over any window
  for (const auto& x : env.seen)
    for (const double xi : x) EXPECT_TRUE(xi >= -1.0 && xi <= 1.0);
  // a corner with the gradient pointing out of the box: only t <= 0, the window [-2H, 0]
  const auto corner = check_large_step(env, *ws, std::vector<double>{1.0, -1.0}, grad, 0.05);
  EXPECT_EQ(corner.hi, 0.0);
  EXPECT_NEAR(corner.lo, -0.1, 1e-15);
  EXPECT_TRUE(corner.directed);
  EXPECT_THROW(check_large_step(env, *ws, std::vector<double>{0.0, 0.0}, grad, 0.6), std::invalid_argument);
  EXPECT_THROW(check_large_step(env, *ws, std::vector<double>{0.0}, grad, 0.05), std::invalid_argument);
}

TEST(GradientCheck, OptionsNameTheBadField) {
  auto message = [](auto mutate) {
    GradientSurveyOptions o;
    mutate(o);
    return testing::validation_message(o);
  };
  EXPECT_NE(message([](auto& o) { o.check.step = 0.0; }).find("'step'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.check.step = 0.5; }).find("'step'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.check.tolerance = 0.0; }).find("'tolerance'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.check.relative_floor = -1.0; }).find("'relative_floor'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.check.absolute_floor = NAN; }).find("'absolute_floor'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.check.value_tolerance = -1e-9; }).find("'value_tolerance'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.points = 0; }).find("'points'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.amplitude = 1.5; }).find("'amplitude'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.large_step = 0.6; }).find("'large_step'"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.large_step = -0.1; }).find("'large_step'"), std::string::npos);
  EXPECT_EQ(message([](auto&) {}), "valid");

  const auto env = smooth_env();
  EXPECT_THROW(check_gradient(env, std::vector<double>{0.0, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(check_gradient(env, std::vector<double>{0.0, 1.5, 0.0, 0.0}), std::invalid_argument);
  const FunctionEnv value_only(
      1, [](std::span<const double> x) { return x[0]; }, nullptr);
  EXPECT_THROW(check_gradient(value_only, std::vector<double>{0.0}), std::invalid_argument);
}

struct Run {
  int code;
  std::string out;
};

Run harness(const std::string& args) {
  const std::string cmd = std::string(DSB_HARNESS_EXE) + " " + args + " 2>/dev/null";
  Run r{-1, ""};
  std::FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  while (const std::size_t n = std::fread(buf, 1, sizeof buf, pipe)) r.out.append(buf, n);
  const int status = ::pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(HarnessGradcheck, JsonHasThePointsAndTheSummary) {
  const auto r = harness("gradcheck --env sphere-3 --points 4 --seed 2 --amplitude 0.6 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("env"), "sphere-3");
  EXPECT_EQ(j.at("dim"), 3);
  EXPECT_EQ(j.at("options").at("points"), 4);
  EXPECT_EQ(j.at("options").at("seed"), 2);
  EXPECT_EQ(j.at("options").at("step"), 1e-6);
  EXPECT_EQ(j.at("options").at("tolerance"), 1e-4);

  // the same survey in this process gives the same numbers (JSON keeps doubles exactly)
  GradientSurveyOptions o;
  o.points = 4;
  o.seed = 2;
  o.amplitude = 0.6;
  const auto s = survey_gradient(*make_env("sphere-3"), o);
  ASSERT_EQ(j.at("points").size(), 4u);
  for (int p = 0; p < 4; ++p) {
    const auto& q = j.at("points")[p];
    EXPECT_EQ(q.at("index"), p);
    EXPECT_EQ(q.at("x").get<std::vector<double>>(), s.x[p]);
    EXPECT_EQ(q.at("loss").get<double>(), s.checks[p].loss);
    EXPECT_EQ(q.at("worst_relative_error").get<double>(), s.checks[p].worst_relative_error);
    EXPECT_EQ(q.at("worst_absolute_error").get<double>(), s.checks[p].worst_absolute_error);
    EXPECT_EQ(q.at("worst_coordinate"), s.checks[p].worst_coordinate);
    EXPECT_EQ(q.at("gradient_norm").get<double>(), s.checks[p].gradient_norm);
    EXPECT_EQ(q.at("passed"), true);
    EXPECT_EQ(q.at("direction_cosine").get<double>(), s.checks[p].direction_cosine);
    for (const char* key : {"value_path_loss", "value_agrees", "max_abs_central", "finite", "exactly_zero",
                            "bit_equal_to_differences", "gradient_agrees"})
      EXPECT_TRUE(q.contains(key)) << key;
  }
  const auto& summary = j.at("summary");
  EXPECT_EQ(summary.at("points"), 4);
  EXPECT_EQ(summary.at("agreeing"), 4);
  EXPECT_EQ(summary.at("agreeing_fraction"), 1.0);
  EXPECT_EQ(summary.at("aligned"), 4);
  EXPECT_EQ(summary.at("opposed"), 0);
  EXPECT_EQ(summary.at("directed"), 4);
  EXPECT_EQ(summary.at("exactly_zero"), 0);
  EXPECT_EQ(summary.at("exactly_zero_fraction"), 0.0);
  EXPECT_EQ(summary.at("non_finite"), 0);
  EXPECT_EQ(summary.at("value_mismatches"), 0);
  EXPECT_EQ(summary.at("gradient_norm").at("min").get<double>(), s.gradient_norm.min);
  EXPECT_EQ(summary.at("gradient_norm").at("q1").get<double>(), s.gradient_norm.q1);
  EXPECT_EQ(summary.at("gradient_norm").at("median").get<double>(), s.gradient_norm.median);
  EXPECT_EQ(summary.at("gradient_norm").at("q3").get<double>(), s.gradient_norm.q3);
  EXPECT_EQ(summary.at("gradient_norm").at("max").get<double>(), s.gradient_norm.max);
  EXPECT_EQ(summary.at("worst_relative_error").get<double>(), s.worst_relative_error);
  EXPECT_EQ(summary.at("worst_point"), s.worst_point);
  EXPECT_EQ(summary.at("worst_coordinate"), s.worst_coordinate);
  EXPECT_TRUE(summary.contains("seconds_per_loss"));
  EXPECT_TRUE(summary.contains("seconds_per_loss_and_grad"));
  EXPECT_EQ(summary.at("passed"), true);
  // the large-step check (default H 0.05): a quadratic's slope along g is |g| over any window
  EXPECT_EQ(j.at("options").at("large_step"), 0.05);
  EXPECT_EQ(summary.at("large_step_directed"), 4);
  EXPECT_EQ(summary.at("large_step_opposed"), 0);
  EXPECT_EQ(summary.at("large_step_flat"), 0);
  EXPECT_EQ(summary.at("large_step_opposed_fraction"), 0.0);
  EXPECT_EQ(summary.at("large_step_ratio").at("median").get<double>(), s.large_step_ratio.median);
  EXPECT_NEAR(summary.at("large_step_ratio").at("min").get<double>(), 1.0, 1e-9);
  for (int p = 0; p < 4; ++p) {
    const auto& l = j.at("points")[p].at("large_step");
    EXPECT_EQ(l.at("ratio").get<double>(), s.large_steps[p].ratio);
    EXPECT_EQ(l.at("opposed"), false);
    EXPECT_EQ(l.at("lo").get<double>(), -0.05);
  }
  // --large-step 0: no large-step fields
  const auto off = nlohmann::json::parse(harness("gradcheck --env sphere-3 --points 2 --large-step 0 --json").out);
  EXPECT_FALSE(off.at("summary").contains("large_step_opposed"));
  EXPECT_FALSE(off.at("points")[0].contains("large_step"));
}

TEST(HarnessGradcheck, AnyFailingPointExitsOneAndTheTableHasTheSummary) {
  // no central difference is good to 1e-15: every point fails
  const auto fail = harness("gradcheck --env cartpole1 --points 2 --tol 1e-15 --json");
  EXPECT_EQ(fail.code, 1);
  const auto j = nlohmann::json::parse(fail.out);
  EXPECT_EQ(j.at("summary").at("passed"), false);
  EXPECT_EQ(j.at("summary").at("agreeing"), 0);

  const auto table = harness("gradcheck --env sphere-2 --points 3");
  EXPECT_EQ(table.code, 0);
  for (const char* text :
       {"gradient agrees with central differences", "gradient within 25 degrees of differences",
        "gradient opposed to differences (cos < 0)", "gradient exactly zero", "|grad|", "loss() != loss_and_grad()",
        "opposed to a step-0.05 difference along it", "step-difference along it / |grad|", "PASS"})
    EXPECT_NE(table.out.find(text), std::string::npos) << text << "\n" << table.out;

  EXPECT_EQ(harness("gradcheck --env sphere-2 --points 0").code, 2);
  EXPECT_EQ(harness("gradcheck --env sphere-2 --step 0.5").code, 2);
  EXPECT_EQ(harness("gradcheck --env sphere-2 --large-step 0.7").code, 2);
}

}  // namespace
}  // namespace dsb
