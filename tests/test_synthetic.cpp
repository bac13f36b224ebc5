// Synthetic test functions: names, analytic gradients against central differences, known
// optima, hand-computed values and the config / config hash.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config_hash.hpp"
#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/registry.hpp"
#include "envs/synthetic/synthetic.hpp"
#include "support/config_error.hpp"

namespace {

// an env through the synthetic families only (no other family involved)
std::unique_ptr<dsb::Env> make(const std::string& name) {
  for (const auto& family : dsb::synthetic_families())
    if (auto env = family.try_make(name)) return env;
  ADD_FAILURE() << "no synthetic family knows '" << name << "'";
  return nullptr;
}

// every synthetic env the gradient and optimum tests cover
std::vector<std::string> covered_names() {
  std::vector<std::string> names;
  for (const char* f : {"sphere", "rosenbrock", "rastrigin", "ackley", "styblinski"})
    for (int d : {1, 2, 5, 10})
      if (!(d == 1 && std::string(f) == "rosenbrock")) names.push_back(std::string(f) + "-" + std::to_string(d));
  names.push_back("branin");
  names.push_back("hartmann6");
  return names;
}

// physical point -> normalized x for the standard box of `name`
std::vector<double> to_normalized(const std::string& name, const std::vector<double>& z) {
  const auto config = dsb::synthetic_config_from_name(name);
  EXPECT_TRUE(config.has_value());
  std::vector<double> x(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) {
    const double c = 0.5 * (config->lower[i] + config->upper[i]);
    const double h = 0.5 * (config->upper[i] - config->lower[i]);
    x[i] = (z[i] - c) / h;
  }
  return x;
}

// the standard env of `name` with x_opt = z* in every coordinate: f itself, unshifted (up to the
// rounding of (z - z*) + z*)
std::unique_ptr<dsb::Env> make_unshifted(const std::string& name) {
  auto config = *dsb::synthetic_config_from_name(name);
  const double z_star = config.function == "rosenbrock" ? 1.0
      : config.function == "styblinski"                 ? -2.903534027771178
                                                        : 0.0;
  config.x_opt.assign(config.dim, z_star);
  return dsb::make_synthetic_env(name, config);
}

// sphere-10's x_opt rounded to 3 decimals, as docs/envs.md quotes it
const std::string kSphere10XoptQuoted = "3.645, -0.705, 2.918, 0.974, -3.471, -3.426, 3.353, 3.285, 1.955, 2.000";

const std::vector<std::string> kShifted = {"sphere", "rosenbrock", "rastrigin", "ackley", "styblinski"};

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double e : v) m = std::max(m, std::abs(e));
  return m;
}

// ---------------------------------------------------------------------------------------------
// names

TEST(SyntheticNames, FamiliesInOrderWithGridMembers) {
  const auto families = dsb::synthetic_families();
  const std::vector<std::string> patterns = {"sphere-D",     "rosenbrock-D", "rastrigin-D", "ackley-D",
                                             "styblinski-D", "branin",       "hartmann6"};
  const std::vector<std::string> grid = {"sphere-10",     "rosenbrock-10", "rastrigin-10", "ackley-10",
                                         "styblinski-10", "branin",        "hartmann6"};
  ASSERT_EQ(families.size(), patterns.size());
  for (std::size_t i = 0; i < families.size(); ++i) {
    EXPECT_EQ(families[i].pattern, patterns[i]);
    EXPECT_FALSE(families[i].description.empty());
    ASSERT_EQ(families[i].grid_names.size(), 1u);
    EXPECT_EQ(families[i].grid_names[0], grid[i]);
  }
}

TEST(SyntheticNames, MembersHaveTheirDimension) {
  struct Case {
    std::string name;
    int dim;
  };
  for (const Case& c : std::vector<Case>{{"sphere-7", 7},
                                         {"sphere-1", 1},
                                         {"rosenbrock-2", 2},
                                         {"rastrigin-3", 3},
                                         {"ackley-12", 12},
                                         {"styblinski-10000", 10000},
                                         {"branin", 2},
                                         {"hartmann6", 6}}) {
    SCOPED_TRACE(c.name);
    const auto env = make(c.name);
    ASSERT_NE(env, nullptr);
    EXPECT_EQ(env->name(), c.name);
    EXPECT_EQ(env->dim(), c.dim);
    EXPECT_TRUE(env->differentiable());
    EXPECT_FALSE(env->supports_rl());
    EXPECT_EQ(env->make_rl(), nullptr);
  }
}

TEST(SyntheticNames, MalformedMembersThrowUsageErrorNamingTheName) {
  for (const std::string bad :
       {"sphere-0", "sphere-abc", "sphere-10x", "sphere-", "sphere--3", "sphere-+3", "sphere-010", "sphere- 3",
        "sphere-3.0", "sphere-10001", "sphere-99999", "sphere-99999999999999999999999", "rosenbrock-1", "rosenbrock-0",
        "rastrigin-0", "ackley-x", "styblinski-0"}) {
    SCOPED_TRACE(bad);
    // through the families directly ...
    bool thrown = false;
    try {
      for (const auto& family : dsb::synthetic_families()) (void)family.try_make(bad);
    } catch (const dsb::UsageError& e) {
      thrown = true;
      const std::string what = e.what();
      EXPECT_NE(what.find("'" + bad + "'"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
    EXPECT_TRUE(thrown);
    // ... and through the registry
    EXPECT_THROW((void)dsb::make_env(bad), dsb::UsageError);
    EXPECT_THROW((void)dsb::synthetic_known_optimum(bad), dsb::UsageError);
  }
}

TEST(SyntheticNames, UnrelatedNamesAreNotClaimed) {
  for (const std::string other : {"", "sphere", "Sphere-3", "spheres-3", "branin2", "branin-2", "hartmann",
                                  "hartmann6-6", "cartpole", "ackley"}) {
    SCOPED_TRACE(other);
    for (const auto& family : dsb::synthetic_families()) EXPECT_EQ(family.try_make(other), nullptr) << family.pattern;
    EXPECT_FALSE(dsb::synthetic_config_from_name(other).has_value());
    EXPECT_FALSE(dsb::synthetic_known_optimum(other).has_value());
  }
  try {
    (void)dsb::make_env("sphere");
    ADD_FAILURE() << "make_env(\"sphere\") did not throw";
  } catch (const dsb::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown env 'sphere'"), std::string::npos) << e.what();
  }
}

TEST(SyntheticNames, RegistryBuildsThemAndGridListsThem) {
  const auto env = dsb::make_env("sphere-7");
  ASSERT_NE(env, nullptr);
  EXPECT_EQ(env->dim(), 7);
  EXPECT_EQ(env->name(), "sphere-7");

  const auto grid = dsb::grid_env_names();
  std::size_t last = 0;
  for (const std::string name :
       {"sphere-10", "rosenbrock-10", "rastrigin-10", "ackley-10", "styblinski-10", "branin", "hartmann6"}) {
    const auto it = std::find(grid.begin(), grid.end(), name);
    ASSERT_NE(it, grid.end()) << name;
    const auto pos = static_cast<std::size_t>(it - grid.begin());
    EXPECT_GE(pos, last) << name << " out of registration order";
    last = pos;
  }
}

TEST(SyntheticNames, WrongSizesAreRejected) {
  const auto env = make("sphere-3");
  std::vector<double> x2(2, 0.0), x3(3, 0.0), g2(2), g3(3);
  EXPECT_THROW((void)env->loss(x2), std::invalid_argument);
  EXPECT_THROW((void)env->loss_and_grad(x2, g3), std::invalid_argument);
  EXPECT_THROW((void)env->loss_and_grad(x3, g2), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// values and gradients

// Hand-computed values of the classic functions at simple points (normalized x, so the affine
// map is exercised too); the scalable ones through make_unshifted.
TEST(SyntheticValues, HandComputedPoints) {
  struct Case {
    std::string name;
    std::vector<double> x;
    double loss;
    std::vector<double> grad;  // normalized units
  };
  const double pi = std::numbers::pi;
  const std::vector<Case> cases = {
      // z = (0.5, -1, 1.5): 0.25 + 1 + 2.25; df/dz = 2z, times halfwidth 5
      {"sphere-3", {0.1, -0.2, 0.3}, 3.5, {5.0, -10.0, 15.0}},
      // z = 0: each of the D-1 terms is (1 - 0)^2; df/dz_i = -2 except the last
      {"rosenbrock-4", {0.0, 0.0, 0.0, 0.0}, 3.0, {-10.0, -10.0, -10.0, 0.0}},
      // z = 1: 10 D + D (1 - 10) = D; df/dz = 2
      {"rastrigin-3", {0.2, 0.2, 0.2}, 3.0, {10.0, 10.0, 10.0}},
      // z = 1, r = 1: 20 (1 - e^-0.2); df/dz_i = 4 e^-0.2 z_i / (D r) = e^-0.2 for D = 4
      {"ackley-4",
       {0.2, 0.2, 0.2, 0.2},
       3.6253849384403636,
       {4.093653765389909, 4.093653765389909, 4.093653765389909, 4.093653765389909}},
      // z = 1: 0.5 (1 - 16 + 5) per coordinate; df/dz = 0.5 (4 - 32 + 5)
      {"styblinski-2", {0.2, 0.2}, -10.0, {-57.5, -57.5}},
      // z = (0, 0): 36 + 10 (1 - t) + 10 = 56 - 5 / (4 pi); df/dz = (-12 c, -12), halfwidth 7.5
      {"branin", {-1.0 / 3.0, -1.0}, 55.602112642270264, {-60.0 / pi * 7.5, -90.0}},
      // z = 0.5 (value from an independent evaluation of the standard definition)
      {"hartmann6", {0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, -0.5053149917022333, {}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const bool fixed = c.name == "branin" || c.name == "hartmann6";
    const auto env = fixed ? make(c.name) : make_unshifted(c.name);
    std::vector<double> g(c.x.size());
    const double f = env->loss_and_grad(c.x, g);
    EXPECT_NEAR(f, c.loss, 1e-12 * std::max(1.0, std::abs(c.loss)));
    for (std::size_t i = 0; i < c.grad.size(); ++i)
      EXPECT_NEAR(g[i], c.grad[i], 1e-11 * std::max(1.0, std::abs(c.grad[i]))) << "i = " << i;
  }
}

// The shifted sphere-3 by hand: sum (z_i - x_opt_i)^2, gradient 2 (z_i - x_opt_i) * halfwidth 5.
TEST(SyntheticValues, ShiftedSphereByHand) {
  const auto env = make("sphere-3");
  const auto x_opt = dsb::synthetic_config_from_name("sphere-3")->x_opt;
  ASSERT_EQ(x_opt.size(), 3u);
  const std::vector<double> x = {0.1, -0.2, 0.3};
  double expected = 0.0;
  std::vector<double> g(3), expected_g(3);
  for (int i = 0; i < 3; ++i) {
    const double dz = 5.0 * x[i] - x_opt[i];
    expected += dz * dz;
    expected_g[i] = 10.0 * dz;
  }
  EXPECT_NEAR(env->loss_and_grad(x, g), expected, 1e-13 * expected);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(g[i], expected_g[i], 1e-12 * std::abs(expected_g[i]));
}

// Every shifted env is its classic function moved: g(z) = f(z - x_opt + z*) at seeded points,
// with f evaluated through make_unshifted at the normalized point of z - x_opt + z*.
TEST(SyntheticValues, ShiftedIsTheClassicFunctionMoved) {
  for (const std::string& f : kShifted)
    for (int d : {2, 7}) {
      const std::string name = f + "-" + std::to_string(d);
      SCOPED_TRACE(name);
      const auto shifted = make(name);
      const auto classic = make_unshifted(name);
      const auto x_opt = dsb::synthetic_config_from_name(name)->x_opt;
      const double z_star = f == "rosenbrock" ? 1.0 : f == "styblinski" ? -2.903534027771178 : 0.0;
      dsb::Rng rng(dsb::fnv1a64(name) + 3);
      for (int k = 0; k < 20; ++k) {
        std::vector<double> x(d), y(d);
        bool inside = true;
        for (int i = 0; i < d; ++i) {
          x[i] = rng.uniform(-1.0, 1.0);
          // the classic env evaluates f at (5 y - z*) + z* = 5 y (rounding aside): w / 5
          y[i] = (5.0 * x[i] - x_opt[i] + z_star) / 5.0;
          inside = inside && std::abs(y[i]) <= 1.0;
        }
        if (!inside) continue;  // the classic env is defined on the box only
        const double a = shifted->loss(x), b = classic->loss(y);
        EXPECT_NEAR(a, b, 1e-12 * std::max(1.0, std::abs(b)));
      }
    }
}

// Analytic gradient (normalized units) vs central differences at seeded random points.
// Step h = 1e-6 in x. Tolerance per component: 1e-6 relative to the larger of the two, plus an
// absolute floor 1e-6 and a rounding allowance 1e-8 |f| (cancellation in f(x+h) - f(x-h) is
// about eps |f| / h = 2e-10 |f|).
TEST(SyntheticGradient, MatchesCentralDifferences) {
  const double h = 1e-6;
  double worst_ratio = 0.0;  // error / tolerance, reported
  for (const std::string& name : covered_names()) {
    SCOPED_TRACE(name);
    const auto env = make(name);
    ASSERT_NE(env, nullptr);
    const int d = env->dim();
    dsb::Rng rng(dsb::fnv1a64(name) ^ 0x5eed);
    dsb::GradientCheckOptions options;
    options.step = h;
    for (int point = 0; point < 8; ++point) {
      std::vector<double> x(d);
      for (double& xi : x) xi = rng.uniform(-0.95, 0.95);
      const auto r = dsb::check_gradient(*env, x, options);
      const double f = r.loss;
      ASSERT_TRUE(std::isfinite(f));
      EXPECT_TRUE(r.value_agrees);  // loss() and loss_and_grad() agree bit for bit
      for (int i = 0; i < d; ++i) {
        const double g = r.coordinates[i].analytic, fd = r.coordinates[i].differences.central;
        const double tol = 1e-6 * std::max(std::abs(fd), std::abs(g)) + 1e-6 + 1e-8 * std::abs(f);
        EXPECT_NEAR(g, fd, tol) << "point " << point << " component " << i;
        worst_ratio = std::max(worst_ratio, std::abs(g - fd) / tol);
      }
    }
  }
  RecordProperty("worst_error_over_tolerance", std::to_string(worst_ratio));
  std::printf("[ info     ] worst |analytic - central| / tolerance = %.3g\n", worst_ratio);
}

// ---------------------------------------------------------------------------------------------
// known optima

// Loss at every documented minimizer equals the documented value and the gradient vanishes
// there. Tolerances: 1e-12 relative (floor 1e-12) on the value and 1e-9 on the largest
// normalized gradient component where the minimizer is exact to double precision; hartmann6's
// minimizer is given to 8 decimals, so 1e-10 on the value and 1e-5 on the gradient.
TEST(SyntheticOptimum, DocumentedValueAndZeroGradient) {
  for (const std::string& name : covered_names()) {
    SCOPED_TRACE(name);
    const auto env = make(name);
    const auto opt = dsb::synthetic_known_optimum(name);
    ASSERT_TRUE(opt.has_value());
    const bool rounded = name == "hartmann6";
    const double value_tol = rounded ? 1e-10 : 1e-12 * std::max(1.0, std::abs(opt->value));
    const double grad_tol = rounded ? 1e-5 : 1e-9;
    std::vector<std::vector<double>> minimizers = {opt->x_physical};
    minimizers.insert(minimizers.end(), opt->other_minimizers.begin(), opt->other_minimizers.end());
    for (const auto& z : minimizers) {
      ASSERT_EQ(static_cast<int>(z.size()), env->dim());
      const auto x = to_normalized(name, z);
      for (double xi : x) {
        EXPECT_GE(xi, -1.0);
        EXPECT_LE(xi, 1.0);
      }
      std::vector<double> g(x.size());
      const double f = env->loss_and_grad(x, g);
      EXPECT_NEAR(f, opt->value, value_tol);
      EXPECT_LE(max_abs(g), grad_tol);
      // a local minimum: every +-1e-3 step along a coordinate goes up
      for (std::size_t i = 0; i < x.size(); ++i)
        for (double step : {-1e-3, 1e-3}) {
          auto y = x;
          y[i] += step;
          EXPECT_GT(env->loss(y), opt->value) << "coordinate " << i << " step " << step;
        }
    }
  }
}

// The shift rule (synthetic.hpp): x_opt has size D, every coordinate in [0.5, 4] in absolute value
// on the 2^-20 grid of the normalized box (so x_opt / 5 is exact), drawn from a fixed seed (the
// same every time), different for every (function, D).
TEST(SyntheticOptimum, ShiftRule) {
  std::vector<std::vector<double>> seen;
  for (const std::string& f : kShifted)
    for (int d : {2, 5, 10, 100, 10000}) {
      const std::string name = f + "-" + std::to_string(d);
      SCOPED_TRACE(name);
      const auto config = dsb::synthetic_config_from_name(name);
      ASSERT_EQ(static_cast<int>(config->x_opt.size()), d);
      EXPECT_EQ(config->x_opt, dsb::synthetic_config_from_name(name)->x_opt);
      double lowest = 4.0, highest = 0.0;
      for (double v : config->x_opt) {
        lowest = std::min(lowest, std::abs(v));
        highest = std::max(highest, std::abs(v));
        const double steps = v / 5.0 * 1048576.0;
        ASSERT_EQ(steps, std::round(steps)) << v;
        ASSERT_EQ(5.0 * (v / 5.0), v);
      }
      EXPECT_GE(lowest, 0.5);
      EXPECT_LE(highest, 4.0);
      if (d == 10000) {  // the draws fill [0.5, 4]
        EXPECT_LT(lowest, 0.51);
        EXPECT_GT(highest, 3.99);
      }
      for (const auto& other : seen) EXPECT_NE(config->x_opt, other);
      seen.push_back(config->x_opt);
    }
  // the value quoted in docs/envs.md (sphere-10, rounded to 3 decimals)
  const auto sphere10 = dsb::synthetic_config_from_name("sphere-10")->x_opt;
  std::string quoted;
  for (double v : sphere10) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%s%.3f", quoted.empty() ? "" : ", ", v);
    quoted += buf;
  }
  std::printf("[ info     ] sphere-10 x_opt = (%s)\n", quoted.c_str());
  EXPECT_EQ(quoted, kSphere10XoptQuoted);
}

// The box centre, where gd and the NLopt local methods start, is no longer (near) a minimizer.
TEST(SyntheticOptimum, CentreIsNotTheOptimum) {
  for (const std::string& name : covered_names()) {
    if (name == "branin" || name == "hartmann6") continue;
    SCOPED_TRACE(name);
    const auto env = make(name);
    const double best = dsb::synthetic_known_optimum(name)->value;
    EXPECT_GT(env->loss(std::vector<double>(env->dim(), 0.0)), best + 0.2);
  }
}

TEST(SyntheticOptimum, DocumentedNumbers) {
  const double pi = std::numbers::pi;
  const auto branin = dsb::synthetic_known_optimum("branin");
  EXPECT_NEAR(branin->value, 0.397887357729738, 1e-15);
  ASSERT_EQ(branin->other_minimizers.size(), 2u);
  EXPECT_EQ(branin->x_physical, (std::vector<double>{-pi, 12.275}));
  EXPECT_EQ(branin->other_minimizers[0], (std::vector<double>{pi, 2.275}));
  EXPECT_NEAR(branin->other_minimizers[1][0], 9.42478, 1e-5);
  EXPECT_EQ(branin->other_minimizers[1][1], 2.475);

  const auto hartmann = dsb::synthetic_known_optimum("hartmann6");
  EXPECT_EQ(hartmann->value, -3.32236801141551);
  // shifted families: the minimizer is the config's x_opt, the value the classic minimum
  for (const std::string name : {"sphere-4", "rosenbrock-3", "ackley-2", "rastrigin-2"}) {
    const auto opt = dsb::synthetic_known_optimum(name);
    EXPECT_EQ(opt->x_physical, dsb::synthetic_config_from_name(name)->x_opt) << name;
    EXPECT_EQ(opt->value, 0.0) << name;
    EXPECT_TRUE(opt->other_minimizers.empty()) << name;
  }
}

// Styblinski-Tang's constants from the 1-D stationarity condition p(z) = 4 z^3 - 32 z + 5 = 0,
// solved here by bisection on [-3, -2.8] (p(-3) = -7 < 0 < p(-2.8)).
TEST(SyntheticOptimum, StyblinskiConstantsSolveStationarity) {
  auto p = [](double z) { return 4.0 * z * z * z - 32.0 * z + 5.0; };
  auto g1 = [](double z) { return 0.5 * (z * z * z * z - 16.0 * z * z + 5.0 * z); };
  double lo = -3.0, hi = -2.8;
  ASSERT_LT(p(lo), 0.0);
  ASSERT_GT(p(hi), 0.0);
  for (int it = 0; it < 200 && hi - lo > 0.0; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (p(mid) < 0.0 ? lo : hi) = mid;
  }
  const double root = 0.5 * (lo + hi);
  EXPECT_NEAR(root, -2.903534027771178, 1e-14);
  EXPECT_NEAR(g1(root), -39.16616570377142, 1e-12);
  // the root is the global minimizer of the 1-D function on [-5, 5]
  for (int k = 0; k <= 100000; ++k) EXPECT_GE(g1(-5.0 + 1e-4 * k), g1(root) - 1e-12);
  for (int d : {1, 3, 10}) {
    const std::string name = "styblinski-" + std::to_string(d);
    const auto opt = dsb::synthetic_known_optimum(name);
    EXPECT_NEAR(opt->value, d * g1(root), 1e-12 * d * 40.0);
    EXPECT_EQ(opt->x_physical, dsb::synthetic_config_from_name(name)->x_opt);
  }
}

// No seeded random point of the box (nor any corner probe) beats the documented optimum.
TEST(SyntheticOptimum, NoRandomPointBelowOptimum) {
  for (const std::string& name : covered_names()) {
    SCOPED_TRACE(name);
    const auto env = make(name);
    const double best = dsb::synthetic_known_optimum(name)->value;
    dsb::Rng rng(dsb::fnv1a64(name) + 17);
    double lowest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 2000; ++k) {
      std::vector<double> x(env->dim());
      for (double& xi : x) xi = k < 50 ? (rng.uniform() < 0.5 ? -1.0 : 1.0) : rng.uniform(-1, 1);
      const double f = env->loss(x);
      ASSERT_TRUE(std::isfinite(f));
      lowest = std::min(lowest, f);
    }
    EXPECT_GE(lowest, best - 1e-12);
    EXPECT_GT(lowest, best);  // random points do not land on the minimizer
  }
}

// Ackley's gradient is undefined at its minimizer (a cone in the radius); it is documented as 0
// there. The normalized minimizer x_opt / 5 is exact, so the env sees exactly z = x_opt.
TEST(SyntheticOptimum, AckleyGradientIsZeroAtTheMinimizer) {
  for (int d : {1, 2, 10}) {
    const std::string name = "ackley-" + std::to_string(d);
    const auto env = make(name);
    std::vector<double> x = dsb::synthetic_config_from_name(name)->x_opt, g(d, 1.0);
    for (double& xi : x) xi /= 5.0;
    EXPECT_EQ(env->loss_and_grad(x, g), 0.0);
    for (double gi : g) EXPECT_EQ(gi, 0.0);
  }
}

// ---------------------------------------------------------------------------------------------
// config

TEST(SyntheticConfig, ConfigDescribesTheBox) {
  const auto sphere = make("sphere-10")->config();
  EXPECT_EQ(sphere.at("function"), "sphere");
  EXPECT_EQ(sphere.at("dim"), 10);
  EXPECT_EQ(sphere.at("lower").get<std::vector<double>>(), std::vector<double>(10, -5.0));
  EXPECT_EQ(sphere.at("upper").get<std::vector<double>>(), std::vector<double>(10, 5.0));
  EXPECT_EQ(sphere.at("x_opt").get<std::vector<double>>(), dsb::synthetic_config_from_name("sphere-10")->x_opt);
  const auto branin = make("branin")->config();
  EXPECT_FALSE(branin.contains("x_opt"));  // not shifted: the classic config, unchanged
  EXPECT_FALSE(make("hartmann6")->config().contains("x_opt"));
  EXPECT_EQ(branin.at("lower").get<std::vector<double>>(), (std::vector<double>{-5.0, 0.0}));
  EXPECT_EQ(branin.at("upper").get<std::vector<double>>(), (std::vector<double>{10.0, 15.0}));
  const auto hartmann = make("hartmann6")->config();
  EXPECT_EQ(hartmann.at("lower").get<std::vector<double>>(), std::vector<double>(6, 0.0));
  EXPECT_EQ(hartmann.at("upper").get<std::vector<double>>(), std::vector<double>(6, 1.0));
  EXPECT_EQ(dsb::synthetic_config_from_name("rastrigin-5")->to_json(), make("rastrigin-5")->config());
}

TEST(SyntheticConfig, HashDistinguishesEnvsAndIsStable) {
  const std::string h10 = dsb::config_hash(make("sphere-10")->config());
  EXPECT_EQ(h10.size(), 16u);
  EXPECT_EQ(h10, dsb::config_hash(make("sphere-10")->config()));
  EXPECT_EQ(h10, dsb::config_hash(dsb::make_env("sphere-10")->config()));
  EXPECT_NE(h10, dsb::config_hash(make("sphere-11")->config()));
  EXPECT_NE(h10, dsb::config_hash(make("rastrigin-10")->config()));
  EXPECT_NE(dsb::config_hash(make("branin")->config()), dsb::config_hash(make("hartmann6")->config()));
  // x_opt is part of the hash
  auto moved = *dsb::synthetic_config_from_name("sphere-10");
  moved.x_opt[3] += 0.25;
  EXPECT_NE(h10, dsb::config_hash(moved.to_json()));
}

TEST(SyntheticConfig, ValidateNamesTheField) {
  const auto good = *dsb::synthetic_config_from_name("rosenbrock-3");
  EXPECT_NO_THROW(good.validate());
  auto expect_field = [](const dsb::SyntheticConfig& c, const std::string& field) {
    dsb::testing::expect_config_error_naming(c, "'" + field + "'");
  };
  auto c = good;
  c.function = "nope";
  expect_field(c, "function");
  c = good;
  c.dim = 1;
  c.lower.resize(1);
  c.upper.resize(1);
  expect_field(c, "dim");  // rosenbrock needs D >= 2
  c = good;
  c.dim = dsb::kSyntheticMaxDim + 1;
  expect_field(c, "dim");
  c = *dsb::synthetic_config_from_name("branin");
  c.dim = 3;
  expect_field(c, "dim");
  c = good;
  c.lower.pop_back();
  expect_field(c, "lower");
  c = good;
  c.upper.push_back(1.0);
  expect_field(c, "upper");
  c = good;
  c.lower[1] = std::numeric_limits<double>::quiet_NaN();
  expect_field(c, "lower");
  c = good;
  c.upper[2] = std::numeric_limits<double>::infinity();
  expect_field(c, "upper");
  c = good;
  c.upper[0] = c.lower[0];
  expect_field(c, "upper");
  c = good;
  c.x_opt.pop_back();
  expect_field(c, "x_opt");
  c = good;
  c.x_opt.clear();
  expect_field(c, "x_opt");
  c = good;
  c.x_opt[1] = 5.5;
  expect_field(c, "x_opt");
  c = good;
  c.x_opt[0] = std::numeric_limits<double>::quiet_NaN();
  expect_field(c, "x_opt");
  c = *dsb::synthetic_config_from_name("branin");
  c.x_opt = {1.0, 1.0};
  expect_field(c, "x_opt");
  EXPECT_THROW((void)dsb::make_synthetic_env("branin", c), dsb::ConfigError);
  // a ConfigError is a UsageError (the harness reports it as bad input)
  c.function = "nope";
  EXPECT_THROW(c.validate(), dsb::UsageError);
}

}  // namespace
