// bounce: the penalty contact law's Jacobians, reverse-pass gradient vs central differences (away
// from contact events, with and without contacts), what happens across one contact event,
// closed-form anchors (symplectic Euler free fall, penalty equilibrium depth), config checks, names.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/registry.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/contact.hpp"
#include "support/contact_jacobian_check.hpp"

namespace dsb {
namespace {

// which surfaces act in every step (bit 1 ground, bit 2 wall), read from the trajectory: a
// contact acts in step t when the state it starts from penetrates (c = r - d > 0)
std::vector<int> contact_pattern(const BounceEnv& env, std::span<const double> x) {
  const auto traj = env.trajectory(x);
  const auto& cfg = env.bounce_config();
  std::vector<int> flags(traj.size() - 1);
  for (std::size_t t = 0; t + 1 < traj.size(); ++t)
    flags[t] = (cfg.radius - traj[t].position.y() > 0.0 ? 1 : 0) |
        (cfg.radius - (cfg.wall_x - traj[t].position.x()) > 0.0 ? 2 : 0);
  return flags;
}

// A point is smooth at scale h when no contact begins or ends within +-h along any coordinate
// (same per-step contact pattern) and the one-sided differences agree.
bool smooth_at(const BounceEnv& env, const std::vector<double>& x, double h) {
  const auto pattern = contact_pattern(env, x);
  for (int i = 0; i < env.dim(); ++i) {
    for (double s : {-h, h}) {
      auto y = x;
      y[i] += s;
      if (contact_pattern(env, y) != pattern) return false;
    }
    const Differences d = finite_differences(env, x, i, h);
    if (std::abs(d.right - d.left) > 1e-2 * (std::abs(d.central) + 1.0)) return false;
  }
  return true;
}

// gradient vs central differences at `points` seeded smooth points; returns the largest
// relative error (|analytic - central| / (|central| + 1))
double expect_gradient_matches(const BounceEnv& env, std::uint64_t seed, int points,
                               int* contact_steps_seen = nullptr) {
  const GradientCheckOptions options = testing::rigid_gradient_check_options();
  Rng rng(seed);
  double worst = 0.0;
  int accepted = 0, tried = 0;
  while (accepted < points && tried < 10 * points) {
    ++tried;
    std::vector<double> x(3);
    for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
    if (!smooth_at(env, x, options.step)) continue;
    ++accepted;
    const auto r = check_gradient(env, x, options);
    EXPECT_TRUE(r.value_agrees) << "loss_and_grad and loss disagree";
    if (contact_steps_seen) {
      const auto c = env.contact_steps(x);
      *contact_steps_seen += c.ground + c.wall;
    }
    for (int i = 0; i < 3; ++i) {
      const auto& c = r.coordinates[i];
      EXPECT_LE(c.relative_error, options.tolerance)
          << "seed " << seed << " point (" << x[0] << ", " << x[1] << ", " << x[2] << ") coordinate " << i
          << ": analytic " << c.analytic << ", central " << c.differences.central;
      worst = std::max(worst, c.relative_error);
    }
  }
  EXPECT_EQ(accepted, points) << "too few smooth points among " << tried;
  return worst;
}

TEST(ContactLaw, PlaneJacobiansMatchCentralDifferences) {
  // force on a ball pressed into a tilted plane, random penetrations and velocities (approach
  // and separation, slow and fast sliding)
  ContactConfig cfg;
  const double r = 0.1, h = 1e-7;
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, 1.0, -0.2).normalized();
  auto force = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& v) {
    return contact_force<3>(cfg, r, plane_geometry<3>(p, n, 0.5), v);
  };
  Rng rng(7);
  double worst = 0.0;
  for (int k = 0; k < 20; ++k) {
    const double depth = rng.uniform(0.001, 0.05);
    Eigen::Vector3d lateral(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
    lateral -= lateral.dot(n) * n;  // along the plane
    const Eigen::Vector3d p = (0.5 + r - depth) * n + lateral;
    const Eigen::Vector3d v(rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0), rng.uniform(-0.5, 0.5));
    const ContactForce<3> c = force(p, v);
    ASSERT_TRUE(c.active);
    EXPECT_NEAR(c.penetration, depth, 1e-12);
    EXPECT_GT(c.f.dot(n), 0.0);  // never pulling
    worst = std::max(worst, testing::expect_contact_jacobians_match<3>(force, p, v, h, k));
  }
  std::printf("plane contact Jacobians: worst relative error %.2e\n", worst);
  // outside the plane's reach there is no force and no derivative
  const ContactForce<3> off = force((0.5 + r + 1e-3) * n, Eigen::Vector3d(0.0, -5.0, 0.0));
  EXPECT_FALSE(off.active);
  EXPECT_EQ(off.f, Eigen::Vector3d::Zero());
  EXPECT_EQ(off.df_dx, Eigen::Matrix3d::Zero());
}

TEST(ContactLaw, NormalForceAndSmoothCoulombValues) {
  // closed form: depth 0.01, approach at 2 m/s, sliding at 3 m/s along x on the ground
  ContactConfig cfg;
  const ContactForce<3> c =
      contact_force<3>(cfg, 0.1, plane_geometry<3>(Eigen::Vector3d(0.0, 0.09, 0.0), Eigen::Vector3d::UnitY(), 0.0),
                       Eigen::Vector3d(3.0, -2.0, 0.0));
  const double fn = 1e4 * 0.01 + 10.0 * 2.0;
  EXPECT_NEAR(c.normal_force, fn, 1e-9);
  EXPECT_NEAR(c.f.y(), fn, 1e-9);
  EXPECT_NEAR(c.f.x(), -0.25 * fn * 3.0 / std::sqrt(9.0 + 0.25), 1e-9);
  EXPECT_EQ(c.f.z(), 0.0);
  // separating: no damping, spring only
  const ContactForce<3> s =
      contact_force<3>(cfg, 0.1, plane_geometry<3>(Eigen::Vector3d(0.0, 0.09, 0.0), Eigen::Vector3d::UnitY(), 0.0),
                       Eigen::Vector3d(0.0, 2.0, 0.0));
  EXPECT_NEAR(s.f.y(), 100.0, 1e-9);
}

TEST(BounceGradient, MatchesCentralDifferencesThroughContacts) {
  const auto env = make_env("bounce");
  const auto& bounce = dynamic_cast<const BounceEnv&>(*env);
  int contact_steps = 0;
  const double worst = expect_gradient_matches(bounce, 101, 12, &contact_steps);
  // several bounces per point on average (a ground bounce lasts about 15 steps)
  EXPECT_GT(contact_steps, 12 * 30);
  std::printf("bounce gradient vs central differences (12 points): worst relative error %.2e\n", worst);
}

TEST(BounceGradient, ContactFreeEpisodeMatchesClosedForm) {
  // 0.05 s (24 steps) cannot reach the ground from y = 1: x_N = x_0 + N dt v_0 + const, so
  // dLoss/dv_0 = N dt (x_N - target) / |x_N - target|
  BounceConfig cfg;
  cfg.duration = 0.05;
  const BounceEnv env(cfg);
  ASSERT_EQ(env.model().steps, 24);
  Rng rng(5);
  for (int point = 0; point < 5; ++point) {
    std::vector<double> x(3);
    for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
    const auto c = env.contact_steps(x);
    ASSERT_EQ(c.ground + c.wall, 0);
    std::vector<double> grad(3);
    const double loss = env.loss_and_grad(x, grad);
    const auto traj = env.trajectory(x);
    const Eigen::Vector3d d = traj.back().position - Eigen::Vector3d(cfg.target[0], cfg.target[1], cfg.target[2]);
    for (int i = 0; i < 3; ++i) {
      const double expected = 24 * cfg.dt * d(i) / loss * 0.5 * (cfg.v_high[i] - cfg.v_low[i]);
      EXPECT_NEAR(grad[i], expected, 1e-12 * std::abs(expected) + 1e-14);
      EXPECT_NEAR(grad[i], finite_differences(env, x, i, 1e-6).central, 1e-7);
    }
  }
}

// A contact event along coordinate i: the bracket [a, b] (b - a <= 1e-12 in x[i]) across which the
// per-step contact pattern changes, found by scanning up from x and bisecting. `onset` tells
// whether the first step that differs is the first step of a contact (a contact begins one step
// earlier or later) or its last one (a contact ends one step earlier or later).
struct ContactEvent {
  std::vector<double> a, b;
  bool onset = false;
};

ContactEvent find_event(const BounceEnv& env, std::vector<double> x, int i, bool want_onset) {
  ContactEvent ev;
  for (int k = 0; k < 20000; ++k, x[i] += 1e-4) {
    std::vector<double> a = x, b = x;
    b[i] += 1e-4;
    const auto pa = contact_pattern(env, a);
    if (contact_pattern(env, b) == pa) continue;
    while (b[i] - a[i] > 1e-12) {
      std::vector<double> mid = a;
      mid[i] = 0.5 * (a[i] + b[i]);
      (contact_pattern(env, mid) == pa ? a : b) = mid;
    }
    const auto pb = contact_pattern(env, b);
    std::size_t t = 0;
    while (pa[t] == pb[t]) ++t;
    const int bit = pa[t] ^ pb[t];
    const auto& with = (pa[t] & bit) ? pa : pb;
    const bool onset = t == 0 || !(with[t - 1] & bit);
    if (onset == want_onset) return {a, b, onset};
  }
  ADD_FAILURE() << "no contact event of the wanted kind found";
  return ev;
}

TEST(BounceGradient, AcrossAContactEventTheGradientIsFiniteAndOneSidedDifferencesDisagree) {
  // Vary vy (x[1]) at fixed vx, vz and bisect to where the per-step contact pattern changes. The
  // loss is piecewise smooth. At a contact onset the damping term -kd min(v_n, 0) acts at once
  // (the force jumps from 0 to about kd |v_n|), so the loss jumps; at a separation the force
  // ke c goes to 0 continuously and the loss only has a kink. Either way the analytic gradient is
  // the derivative of the piece it is evaluated in: finite, and blind to the event.
  const auto env = make_env("bounce");
  const auto& bounce = dynamic_cast<const BounceEnv&>(*env);
  for (const bool onset : {true, false}) {
    const ContactEvent ev = find_event(bounce, {0.3, -0.2, -0.4}, 1, onset);
    ASSERT_FALSE(ev.a.empty());
    const std::vector<double>& a = ev.a;
    std::vector<double> grad(3);
    const double loss = env->loss_and_grad(a, grad);
    ASSERT_TRUE(std::isfinite(loss));
    for (double g : grad) EXPECT_TRUE(std::isfinite(g));
    // one-sided differences over h = 1e-6: the left one stays in a's piece, the right one crosses
    const double h = 1e-6;
    std::vector<double> left = a, right = a;
    left[1] -= h;
    right[1] += h;
    ASSERT_EQ(contact_pattern(bounce, left), contact_pattern(bounce, a));
    const double d_left = (loss - env->loss(left)) / h;
    const double d_right = (env->loss(right) - loss) / h;
    const double jump = env->loss(ev.b) - loss;
    std::printf(
        "%s event at x[1] = %.15f: loss change over 1e-12 %.3e, one-sided differences "
        "%.6e (left) %.6e (right), analytic %.6e\n",
        onset ? "onset" : "separation", a[1], jump, d_left, d_right, grad[1]);
    EXPECT_NEAR(grad[1], d_left, 1e-3 * std::abs(d_left) + 1e-3);           // the gradient of a's piece
    EXPECT_GT(std::abs(d_right - d_left), 0.1 * (std::abs(d_left) + 1.0));  // they disagree
    if (onset)
      EXPECT_GT(std::abs(jump), 1e-6);  // a jump of the loss itself
    else
      EXPECT_LT(std::abs(jump), 1e-9);  // continuous (1e-12 times a slope of order 10)
  }
}

TEST(BounceGradient, ZeroAtZeroDistance) {
  BounceConfig cfg;
  const std::vector<double> x = {0.2, -0.3, 0.5};
  cfg.target = {0.0, 0.0, 0.0};
  const auto final_position = BounceEnv(cfg).trajectory(x).back().position;
  cfg.target = {final_position.x(), final_position.y(), final_position.z()};
  const BounceEnv env(cfg);
  std::vector<double> grad(3, 1.0);
  EXPECT_EQ(env.loss_and_grad(x, grad), 0.0);
  for (double g : grad) EXPECT_EQ(g, 0.0);
}

TEST(BounceDynamics, FreeFallMatchesTheSymplecticEulerRecursion) {
  // before the first contact: x_n = x_0 + n dt v_0 - g dt^2 n (n + 1) / 2 e_y
  const auto env = make_env("bounce");
  const auto& bounce = dynamic_cast<const BounceEnv&>(*env);
  const auto& cfg = bounce.bounce_config();
  const std::vector<double> x = {0.1, 0.8, -0.3};  // vy = -1.9 m/s: about 0.25 s of flight
  const auto traj = bounce.trajectory(x);
  ASSERT_EQ(traj.size(), 961u);
  const Eigen::Vector3d x0(cfg.start[0], cfg.start[1], cfg.start[2]);
  const Eigen::Vector3d v0 = bounce.initial_velocity(x);
  int n = 0;
  double worst = 0.0;
  for (; n < 960 && traj[n].position.y() >= cfg.radius; ++n) {
    const double dn = n;
    Eigen::Vector3d expected = x0 + dn * cfg.dt * v0;
    expected.y() -= cfg.gravity * cfg.dt * cfg.dt * dn * (dn + 1.0) / 2.0;
    worst = std::max(worst, (traj[n].position - expected).cwiseAbs().maxCoeff());
    EXPECT_NEAR((traj[n].velocity - v0 + Eigen::Vector3d(0.0, cfg.gravity * cfg.dt * dn, 0.0)).norm(), 0.0, 1e-12);
  }
  EXPECT_GT(n, 100);  // the check covers the whole flight
  EXPECT_LT(worst, 1e-12);
  std::printf("free fall over %d steps: largest deviation from the closed form %.2e m\n", n, worst);
}

TEST(BounceDynamics, RestingBallSettlesAtThePenaltyEquilibriumDepth) {
  // a ball placed on the ground at rest sinks until ke c = m g: depth m g / ke (0.981 mm)
  BounceConfig cfg;
  cfg.start = {0.0, cfg.radius, 0.0};
  cfg.v_low = {0.0, 0.0, 0.0};
  cfg.v_high = {0.0, 0.0, 0.0};
  cfg.duration = 10.0;
  const BounceEnv env(cfg);
  const std::vector<double> x = {0.0, 0.0, 0.0};
  const auto traj = env.trajectory(x);
  const double depth = cfg.mass * cfg.gravity / cfg.contact.ke;
  double deepest = 0.0;
  for (const auto& s : traj) deepest = std::max(deepest, cfg.radius - s.position.y());
  const double final_depth = cfg.radius - traj.back().position.y();
  std::printf("resting ball: final depth %.9e m (m g / ke = %.9e), deepest %.3e m\n", final_depth, depth, deepest);
  EXPECT_NEAR(final_depth, depth, 1e-6 * depth);
  EXPECT_LT(traj.back().velocity.norm(), 1e-6);
  EXPECT_GT(deepest, 1.5 * depth);  // it overshot and the damping brought it back: not vacuous
}

TEST(BounceEnv, NonFiniteStateGivesNaNLossAndGradient) {
  // a throw at 1e308 m/s puts the ball 2e305 m into the wall after one step: the contact force
  // overflows to inf and the state becomes NaN
  BounceConfig cfg;
  cfg.v_low[0] = cfg.v_high[0] = 1e308;
  const BounceEnv env(cfg);
  BallState bad;
  bad.velocity.y() = std::nan("");
  EXPECT_TRUE(std::isnan(env.final_loss(bad)));
  const std::vector<double> x = {0.0, 0.0, 0.0};
  EXPECT_TRUE(std::isnan(env.loss(x)));
  std::vector<double> grad(3, 0.0);
  EXPECT_TRUE(std::isnan(env.loss_and_grad(x, grad)));
  for (double g : grad) EXPECT_TRUE(std::isnan(g));
}

TEST(BounceEnv, ParameterMapDimensionsAndDeterminism) {
  const auto env = make_env("bounce");
  EXPECT_EQ(env->name(), "bounce");
  EXPECT_EQ(env->dim(), 3);
  EXPECT_TRUE(env->differentiable());
  EXPECT_FALSE(env->supports_rl());
  const auto& bounce = dynamic_cast<const BounceEnv&>(*env);
  EXPECT_EQ(bounce.model().steps, 960);
  const std::vector<double> lo = {-1.0, -1.0, -1.0}, hi = {1.0, 1.0, 1.0}, mid = {0.0, 0.0, 0.0};
  EXPECT_EQ(bounce.initial_velocity(lo), Eigen::Vector3d(-10.0, -10.0, -10.0));
  EXPECT_EQ(bounce.initial_velocity(hi), Eigen::Vector3d(10.0, -1.0, 10.0));
  EXPECT_EQ(bounce.initial_velocity(mid), Eigen::Vector3d(0.0, -5.5, 0.0));
  // bit-identical reruns, also from a second instance
  const std::vector<double> x = {0.37, -0.81, 0.12};
  const double l = env->loss(x);
  EXPECT_TRUE(std::isfinite(l));
  EXPECT_EQ(env->loss(x), l);
  EXPECT_EQ(make_env("bounce")->loss(x), l);
  std::vector<double> g1(3), g2(3);
  EXPECT_EQ(env->loss_and_grad(x, g1), l);
  env->loss_and_grad(x, g2);
  EXPECT_EQ(g1, g2);
  EXPECT_EQ(env->config()["steps"], 960);
}

TEST(BounceNames, AVariantIsRefusedAsBounceTakesNone) {
  auto message = [](const std::string& name) -> std::string {
    try {
      (void)make_env(name);
    } catch (const UsageError& e) {
      return e.what();
    }
    return "no error";
  };
  for (const std::string bad : {"bounce-", "bounce-2", "bounce_x"})
    EXPECT_EQ(message(bad), "unknown env '" + bad + "' (bounce takes no variants)");
  EXPECT_EQ(message("bouncex"), "unknown env 'bouncex' (see `harness list`)");  // no family knows it
  EXPECT_EQ(make_env("bounce")->name(), "bounce");
}

TEST(BounceConfigTest, ValidationNamesTheField) {
  auto message = [](const BounceConfig& cfg) -> std::string {
    try {
      cfg.validate();
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  BounceConfig cfg;
  EXPECT_EQ(message(cfg), "");
  cfg.radius = 0.0;
  EXPECT_NE(message(cfg).find("'radius'"), std::string::npos) << message(cfg);
  cfg = BounceConfig{};
  cfg.v_high[1] = -20.0;
  EXPECT_NE(message(cfg).find("'v_high'"), std::string::npos) << message(cfg);
  cfg = BounceConfig{};
  cfg.contact.kd = -1.0;
  EXPECT_NE(message(cfg).find("'contact.kd'"), std::string::npos) << message(cfg);
  cfg = BounceConfig{};
  cfg.contact.friction_smoothing = 0.0;
  EXPECT_NE(message(cfg).find("'contact.friction_smoothing'"), std::string::npos) << message(cfg);
  cfg = BounceConfig{};
  cfg.dt = std::nan("");
  EXPECT_NE(message(cfg).find("'dt'"), std::string::npos) << message(cfg);
  EXPECT_THROW(BounceEnv{cfg}, std::exception);
}

}  // namespace
}  // namespace dsb
