// cartpole1 / cartpole3: reverse-pass gradient vs central differences, closed-form checks of the
// dynamics (energy of the free chain, the physical pendulum's period), RL interface parity.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/registry.hpp"
#include "envs/rigid/cartpole_env.hpp"

namespace dsb {
namespace {

std::vector<double> random_point(Rng& rng, int dim, double amplitude) {
  std::vector<double> x(dim);
  for (auto& xi : x) xi = amplitude * rng.uniform(-1.0, 1.0);
  return x;
}

void expect_gradient_matches(const std::string& name, double amplitude, std::uint64_t seed) {
  const auto env = make_env(name);
  // |analytic - central| <= 1e-6 (|central| + 0.1 max_j |central_j|): a relative tolerance with
  // an absolute floor scaled by the largest component; loss() and loss_and_grad() bit-equal
  GradientCheckOptions options;
  options.step = 1e-6;
  options.tolerance = 1e-6;
  options.relative_floor = 0.1;
  Rng rng(seed);
  for (int point = 0; point < 3; ++point) {
    const auto x = random_point(rng, env->dim(), amplitude);
    const auto r = check_gradient(*env, x, options);
    ASSERT_TRUE(std::isfinite(r.loss));
    EXPECT_TRUE(r.value_agrees) << "loss_and_grad and loss disagree";
    ASSERT_GT(r.max_abs_central, 1e-3) << "degenerate test point";
    for (std::size_t i = 0; i < r.coordinates.size(); ++i)
      EXPECT_LE(r.coordinates[i].relative_error, options.tolerance)
          << name << " point " << point << " coordinate " << i << ": analytic " << r.coordinates[i].analytic
          << ", central " << r.coordinates[i].differences.central;
    EXPECT_TRUE(r.passed) << name << " point " << point << ": worst coordinate " << r.worst_coordinate;
  }
}

TEST(CartpoleGradient, OneLinkMatchesCentralDifferences) {
  expect_gradient_matches("cartpole1", 0.3, 11);
  expect_gradient_matches("cartpole1", 1.0, 12);
}

TEST(CartpoleGradient, ThreeLinksMatchesCentralDifferences) {
  expect_gradient_matches("cartpole3", 0.1, 21);
  expect_gradient_matches("cartpole3", 0.3, 22);
}

TEST(CartpoleGradient, ZeroControlsStayAtRestWithKnownLoss) {
  // hanging down at rest with no input stays put: tip at (0, -3), loss = |(0,-3) - (1, 2.5)|
  const auto env = make_env("cartpole3");
  std::vector<double> x(env->dim(), 0.0);
  EXPECT_DOUBLE_EQ(env->loss(x), std::hypot(1.0, 5.5));
}

TEST(CartpoleDynamics, FreeChainEnergyStaysNearItsStartValue) {
  // cart held still (u = 0) and no torques: the three-link chain released from a large angle
  // conserves energy up to the O(dt) drift of semi-implicit Euler, which stays bounded
  CartpoleConfig cfg = CartpoleConfig::three_links();
  cfg.start_joint_angles = {1.2, -0.5, 0.8};
  cfg.steps = 2000;
  cfg.dt = 0.001;
  const CartpoleModel model = CartpoleModel::build(cfg);
  CartpoleState s = cartpole_initial_state(model, cfg);
  const double e0 = cartpole_chain_energy(model, s, cfg);
  const double tau[3] = {0.0, 0.0, 0.0};
  double max_dev = 0.0;
  for (int t = 0; t < cfg.steps; ++t) {
    cartpole_step(model, s, 0.0, tau);
    max_dev = std::max(max_dev, std::abs(cartpole_chain_energy(model, s, cfg) - e0));
  }
  // energy scale: potential difference of the start pose is several J
  EXPECT_LT(max_dev, 0.02 * std::abs(e0)) << "e0 = " << e0;
  EXPECT_GT(max_dev, 0.0);  // the integrator is not exact: the check is not vacuous
}

TEST(CartpoleDynamics, SingleLinkSwingsWithThePendulumPeriod) {
  // uniform rod about its end: T = 2 pi sqrt(I_pivot / (m g L/2)) = 2 pi sqrt(2 L / (3 g))
  CartpoleConfig cfg = CartpoleConfig::one_link();
  cfg.start_joint_angles = {0.02};
  cfg.dt = 0.001;
  const CartpoleModel model = CartpoleModel::build(cfg);
  CartpoleState s = cartpole_initial_state(model, cfg);
  const double tau[1] = {0.0};
  std::vector<double> crossings;  // times of downward zero crossings of phi, linearly interpolated
  double t = 0.0;
  for (int step = 0; step < 20000 && crossings.size() < 6; ++step) {
    const double before = s.phi(0);
    cartpole_step(model, s, 0.0, tau);
    t += cfg.dt;
    if (before > 0.0 && s.phi(0) <= 0.0) crossings.push_back(t - cfg.dt + cfg.dt * before / (before - s.phi(0)));
  }
  ASSERT_EQ(crossings.size(), 6u);
  const double measured = (crossings.back() - crossings.front()) / 5.0;
  const double expected = 2.0 * std::numbers::pi * std::sqrt(2.0 * cfg.link_length / (3.0 * cfg.gravity));
  EXPECT_NEAR(measured, expected, 1e-4 * expected) << "measured " << measured;
}

TEST(CartpoleDynamics, CartSpeedFollowsTheCommandExactly) {
  const auto env = make_env("cartpole1");
  std::vector<double> x(env->dim(), 0.0);
  for (int t = 0; t < 100; ++t) x[2 * t] = 0.2;  // 1 m/s for 1 s
  const auto& cart = dynamic_cast<const CartpoleEnv&>(*env);
  const auto traj = cart.trajectory(x);
  EXPECT_DOUBLE_EQ(traj.back().vx, 1.0);
  EXPECT_NEAR(traj.back().x, 1.0, 1e-12);
}

// the parameter map (the references drive their engines with it): step-major, cart speed then
// one torque per joint, x = +-1 at +-5 m/s and +-30 N m
TEST(CartpoleDynamics, ControlsAreTheDocumentedAffineMap) {
  const CartpoleEnv env("cartpole3", CartpoleConfig::three_links());
  std::vector<double> x(env.dim(), 0.0);
  const double step7[4] = {1.0, -1.0, 0.5, 0.25};
  for (int k = 0; k < 4; ++k) x[4 * 7 + k] = step7[k];
  const CartpoleControls c = env.controls(x, 7);
  EXPECT_EQ(c.u, 5.0);
  EXPECT_EQ(c.tau[0], -30.0);
  EXPECT_EQ(c.tau[1], 15.0);
  EXPECT_EQ(c.tau[2], 7.5);
  for (int t : {6, 8}) {
    const CartpoleControls rest = env.controls(x, t);
    EXPECT_EQ(rest.u, 0.0) << t;
    for (int j = 0; j < 3; ++j) EXPECT_EQ(rest.tau[j], 0.0) << t;
  }
}

TEST(CartpoleRl, StepInterfaceGivesTheSameLossAsTheRollout) {
  const auto env = make_env("cartpole3");
  Rng rng(5);
  const auto x = random_point(rng, env->dim(), 0.5);
  auto rl = env->make_rl();
  ASSERT_NE(rl, nullptr);
  EXPECT_EQ(rl->action_dim(), 4);
  EXPECT_EQ(rl->horizon(), 100);
  // the paper's observation: the joint positions and velocities (x, vx, phi_1..3, dphi_1..3), no time
  EXPECT_EQ(rl->observation_dim(), 8);
  rl->reset();
  const auto states = dynamic_cast<const CartpoleEnv&>(*env).trajectory(x);
  for (int t = 0; t < rl->horizon(); ++t) {
    ASSERT_FALSE(rl->done());
    const auto obs = rl->observe();
    ASSERT_EQ(obs.size(), 8u);
    const CartpoleState& s = states[static_cast<std::size_t>(t)];
    const std::vector<double> want = {s.x, s.vx, s.phi(0), s.phi(1), s.phi(2), s.dphi(0), s.dphi(1), s.dphi(2)};
    EXPECT_EQ(obs, want) << t;
    rl->step(std::span<const double>(x).subspan(4 * t, 4));
  }
  EXPECT_TRUE(rl->done());
  EXPECT_EQ(rl->final_loss(), env->loss(x));  // bit-identical
}

TEST(CartpoleConfigTest, ValidationNamesTheField) {
  CartpoleConfig cfg = CartpoleConfig::three_links();
  cfg.link_masses = {1.0, 0.5};
  try {
    cfg.validate();
    FAIL() << "expected ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("link_masses"), std::string::npos) << e.what();
  }
  cfg = CartpoleConfig::three_links();
  cfg.dt = -1.0;
  EXPECT_THROW(cfg.validate(), std::exception);
}

TEST(CartpoleFamily, NamesAndDimensions) {
  EXPECT_EQ(make_env("cartpole1")->dim(), 200);
  EXPECT_EQ(make_env("cartpole3")->dim(), 400);
  EXPECT_TRUE(make_env("cartpole3")->differentiable());
}

}  // namespace
}  // namespace dsb
