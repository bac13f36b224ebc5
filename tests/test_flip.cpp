// The `flip` task (envs/cloth/flip_*) and its pan (envs/cloth/pan_surface.*): config facts
// (stability, validation), the pan's distance, normal and velocity derivatives and its parameter
// adjoint vs differences, gradients vs central differences at seeded points away from contact
// switches and what happens across one, the pinned flip, identical reruns, bad names, the RL view
// (replaying a param vector), the harness end to end, and the forward / gradient episode times
// (printed, not asserted).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/cloth/flip_env.hpp"
#include "envs/cloth/pan_surface.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/core/lazy_model.hpp"
#include "envs/registry.hpp"
#include "support/config_error.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"
#include "tests/support/contact_window.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using cloth::FlipEnv;
using cloth::Mat3;
using cloth::PanPose;
using cloth::PanSurface;
using cloth::Vec3;

const FlipEnv& flip() { return dynamic_cast<const FlipEnv&>(*shared_env("flip")); }

TEST(FlipConfig, DefaultsAreValidAndStoredWithTheRun) {
  const cloth::FlipConfig cfg;
  EXPECT_NO_THROW(cfg.validate());
  EXPECT_EQ(cfg.segment_steps(), 120);
  EXPECT_EQ(cfg.steps(), 1000);
  const auto j = flip().config();
  EXPECT_EQ(j["steps"], 1000);
  EXPECT_EQ(j["pan_radius"], 0.2);  // the seed's 20 cm
  EXPECT_EQ(j["flip_example"].size(), 15u);
  EXPECT_EQ(flip().dim(), 15);
  EXPECT_EQ(flip().model().cloth.vertices(), 81);
  EXPECT_TRUE(flip().differentiable());
  EXPECT_TRUE(flip().supports_rl());
}

TEST(FlipConfig, InvalidFieldsAreNamed) {
  auto expect_field = [](const cloth::FlipConfig& c, const std::string& field) {
    testing::expect_config_error_naming(c, field);
  };
  cloth::FlipConfig c;
  c.dt = 0.0;
  expect_field(c, "dt");
  c = {};
  c.side = 0.25;  // half-diagonal beyond the flat bottom
  expect_field(c, "side");
  c = {};
  c.pan.flat_radius = 0.3;
  expect_field(c, "flat_radius");
  c = {};
  c.pan.thickness = 0.0;
  expect_field(c, "thickness");
  c = {};
  c.control_steps = 7;
  expect_field(c, "control_steps");
  c = {};
  c.flip_example.pop_back();
  expect_field(c, "flip_example");
  c = {};
  c.half_range[2] = -1.0;
  expect_field(c, "half_range");
  c = {};
  c.tangential_keep = 1.5;
  expect_field(c, "tangential_keep");
  c = {};
  c.floor_height = 0.0;
  expect_field(c, "floor_height");
}

TEST(FlipModel, StableAndAStillPanLeavesThePancakeWhereItIs) {
  const auto& env = flip();
  const auto& m = env.model();
  const double w_dt = cloth::frequency_bound(m.cloth, m.stiffness) * env.flip_config().dt;
  std::printf("frequency_bound * dt: %.3f\n", w_dt);
  EXPECT_LT(w_dt, 0.6);
  // all params 0: the pan never moves; the pancake settles on the bottom, face up, not flipped
  const std::vector<double> zero(15, 0.0);
  const auto s = env.final_state(zero);
  double lowest = 1e9, highest = -1e9;
  for (const auto& p : s.x) {
    lowest = std::min(lowest, p.y());
    highest = std::max(highest, p.y());
  }
  std::printf("still pan: final heights [%.5f, %.5f] m, loss %.6f m, orientation %.4f\n", lowest, highest,
              env.loss(zero), env.orientation(s, PanPose{}));
  EXPECT_GT(lowest, -2e-3);
  EXPECT_LT(highest, 2e-3);
  EXPECT_NEAR(env.loss(zero), env.flip_config().side, 1e-3);  // every corner a side length from its target
  EXPECT_GT(env.orientation(s, PanPose{}), 0.999);
  // the pose path: waypoint 0 at t = 0, waypoint k at k segment_steps, held after the fifth
  std::vector<double> x(15);
  for (int i = 0; i < 15; ++i) x[i] = 0.1 * (i + 1) - 0.8;
  const auto path = env.pose_path(x);
  const auto w = env.waypoints(x);
  ASSERT_EQ(path.size(), 1001u);
  EXPECT_EQ(path[0].x, 0.0);
  for (int k = 1; k <= 5; ++k) {
    EXPECT_NEAR(path[k * 120].x, w[k].x, 1e-15);
    EXPECT_NEAR(path[k * 120].y, w[k].y, 1e-15);
    EXPECT_NEAR(path[k * 120].tilt, w[k].tilt, 1e-15);
  }
  EXPECT_EQ(path[1000].tilt, w[5].tilt);
  EXPECT_NEAR(w[1].x, x[0] * 0.15, 1e-15);
  EXPECT_NEAR(w[5].tilt, x[14] * 1.2, 1e-15);
}

// --- the pan -------------------------------------------------------------------------------

TEST(PanSurface, ProfileIsC2AtTheJoinAndReachesTheRim) {
  const cloth::PanShape shape;
  double h0, d0, s0, h1, d1, s1;
  shape.profile(shape.flat_radius, h0, d0, s0);
  shape.profile(shape.flat_radius + 1e-9, h1, d1, s1);
  EXPECT_EQ(h0, 0.0);
  EXPECT_NEAR(h1, 0.0, 1e-20);
  EXPECT_NEAR(d1, 0.0, 1e-12);
  EXPECT_NEAR(s1, 0.0, 1e-5);  // h'' = 6 H u / w^2 -> 0
  shape.profile(shape.radius, h1, d1, s1);
  EXPECT_NEAR(h1, shape.rim_height, 1e-15);
  EXPECT_NEAR(d1, 3.0 * shape.rim_height / (shape.radius - shape.flat_radius), 1e-12);
  // h' and h'' against differences of h on the rim
  const double r = 0.17, e = 1e-6;
  double hp, hm, dp, dm, h, d, s;
  shape.profile(r, h, d, s);
  shape.profile(r + e, hp, dp, s1);
  shape.profile(r - e, hm, dm, s1);
  EXPECT_NEAR(d, (hp - hm) / (2 * e), 1e-8);
  EXPECT_NEAR(s, (dp - dm) / (2 * e), 1e-6);
}

// a pan with a 2-step path of general poses (dt 1e-3)
PanSurface posed_pan(const PanPose& p0, const PanPose& p1) {
  PanSurface pan(cloth::PanShape{});
  const std::vector<PanPose> path = {p0, p1, p1};
  pan.set_path(path, 1e-3);
  return pan;
}

TEST(PanSurface, NormalVelocityAndTheirJacobiansMatchDifferences) {
  const PanPose p0{0.03, -0.02, 0.4}, p1{0.031, -0.0185, 0.41};
  const PanSurface pan = posed_pan(p0, p1);
  // points in pan-local coordinates: on the disc, on the rim (several azimuths), above the rim
  const std::vector<Vec3> local = {
      {0.02, 0.003, -0.05}, {0.16, 0.0, 0.03}, {-0.05, 0.0, 0.175}, {0.12, 0.0, -0.12}, {-0.18, 0.01, 0.0}};
  const double e = 1e-6;
  for (std::size_t k = 0; k < local.size(); ++k) {
    Vec3 l = local[k];
    double hh, dh, d2h;
    const double r = std::sqrt(l.x() * l.x() + l.z() * l.z());
    pan.shape().profile(r, hh, dh, d2h);
    l.y() += hh;  // on (or a little above) the surface
    const Vec3 x = PanSurface::to_world(p0, l);
    const auto q = pan.sample(0, x);
    ASSERT_LE(q.distance, 0.011) << k;
    ASSERT_GT(q.distance, -0.02) << k;
    EXPECT_NEAR(q.normal.norm(), 1.0, 1e-14);
    Mat3 dn, du;
    Vec3 dd;
    for (int c = 0; c < 3; ++c) {
      Vec3 xp = x, xm = x;
      xp(c) += e;
      xm(c) -= e;
      const auto a = pan.sample(0, xp), b = pan.sample(0, xm);
      dn.col(c) = (a.normal - b.normal) / (2 * e);
      du.col(c) = (a.velocity - b.velocity) / (2 * e);
      dd(c) = (a.distance - b.distance) / (2 * e);
    }
    const double err_n = (dn - q.dnormal_dx).cwiseAbs().maxCoeff();
    const double err_u = (du - q.dvelocity_dx).cwiseAbs().maxCoeff();
    std::printf("pan point %zu (r %.3f): |dn/dx - diff| %.2e (|dn/dx| %.2f), |du/dx - diff| %.2e\n", k, r, err_n,
                q.dnormal_dx.cwiseAbs().maxCoeff(), err_u);
    EXPECT_LT(err_n, 1e-6) << k;
    EXPECT_LT(err_u, 1e-6) << k;
    // on the surface the distance's gradient is the normal (first-order distance to the graph)
    if (std::abs(l.y() - hh) < 1e-15) {
      EXPECT_LT((dd - q.normal).norm(), 1e-6) << k;
    }
    // velocity of a rigid motion: vc + omega z x (x - c)
    const double omega = (p1.tilt - p0.tilt) / 1e-3;
    const Vec3 d = x - Vec3(p0.x, p0.y, 0.0);
    const Vec3 u = Vec3((p1.x - p0.x) / 1e-3, (p1.y - p0.y) / 1e-3, 0.0) + omega * Vec3(-d.y(), d.x(), 0.0);
    EXPECT_LT((q.velocity - u).norm(), 1e-12);
  }
  // no pan beyond the outer radius or under the shell
  EXPECT_EQ(pan.sample(0, PanSurface::to_world(p0, Vec3(0.21, 0.0, 0.0))).distance, 1.0);
  EXPECT_EQ(pan.sample(0, PanSurface::to_world(p0, Vec3(0.0, -0.03, 0.0))).distance, 1.0);
  EXPECT_NEAR(pan.sample(0, PanSurface::to_world(p0, Vec3(0.0, -0.01, 0.05))).distance, -0.01, 1e-15);
}

TEST(PanSurface, PoseAdjointMatchesDifferences) {
  // f(path) = nb . normal + ub . velocity of the sample at fixed x; sample_adjoint's param_bar vs
  // central differences over the 6 pose entries of rows 0 and 1
  const std::vector<PanPose> base = {{0.03, -0.02, 0.4}, {0.031, -0.0185, 0.41}, {0.0, 0.0, 0.0}};
  const Vec3 nb(0.3, -0.7, 0.2), ub(-0.4, 0.5, 0.9);
  const std::vector<Vec3> local = {{0.02, 0.0, -0.05}, {0.16, 0.004, 0.03}, {-0.05, -0.002, 0.175}};
  for (const Vec3& l : local) {
    double hh, dh, d2h;
    cloth::PanShape{}.profile(std::sqrt(l.x() * l.x() + l.z() * l.z()), hh, dh, d2h);
    const Vec3 x = PanSurface::to_world(base[0], Vec3(l.x(), l.y() + hh, l.z()));
    PanSurface pan(cloth::PanShape{});
    pan.set_path(base, 1e-3);
    std::vector<double> bar(pan.param_count(), 0.0);
    pan.sample_adjoint(0, x, nb, ub, bar);
    auto f = [&](const std::vector<PanPose>& path) {
      PanSurface p(cloth::PanShape{});
      p.set_path(path, 1e-3);
      const auto q = p.sample(0, x);
      return nb.dot(q.normal) + ub.dot(q.velocity);
    };
    double worst = 0.0, scale = 0.0;
    for (int row = 0; row < 2; ++row)
      for (int c = 0; c < 3; ++c) {
        const double e = 1e-7;
        auto plus = base, minus = base;
        double* pp = c == 0 ? &plus[row].x : c == 1 ? &plus[row].y : &plus[row].tilt;
        double* pm = c == 0 ? &minus[row].x : c == 1 ? &minus[row].y : &minus[row].tilt;
        *pp += e;
        *pm -= e;
        const double fd = (f(plus) - f(minus)) / (2 * e);
        worst = std::max(worst, std::abs(fd - bar[3 * row + c]));
        scale = std::max(scale, std::abs(fd));
      }
    std::printf("pan pose adjoint at local (%.3f, %.3f): worst |adjoint - difference| %.2e of %.2e\n", l.x(), l.z(),
                worst, scale);
    EXPECT_LT(worst, 1e-6 * scale + 1e-9);
    for (std::size_t i = 6; i < bar.size(); ++i) EXPECT_EQ(bar[i], 0.0);
  }
}

// --- the task ------------------------------------------------------------------------------

TEST(FlipTask, ThePinnedParamsFlipThePancake) {
  const auto& env = flip();
  const auto& x = env.flip_config().flip_example;
  const auto s = env.final_state(x);
  const double loss = env.loss(x);
  const auto w = env.waypoints(x);
  const auto& m = env.model();
  std::printf("flip example: loss %.5f m, orientation %.4f, final pan pose (%.3f, %.3f, %.3f)\n", loss,
              env.orientation(s, w[5]), w[5].x, w[5].y, w[5].tilt);
  EXPECT_LT(loss, 0.005);                      // measured 2.4 mm (the still pan: 0.14 m)
  EXPECT_LT(env.orientation(s, w[5]), -0.99);  // face down
  // in the pan frame every corner crossed to the other side (x -> -x) and lies on the bottom
  for (int k = 0; k < 4; ++k) {
    const Vec3 start = m.cloth.rest_position[m.corners[k]];
    const Vec3 l = s.x[m.corners[k]] - Vec3(w[5].x, w[5].y, 0.0);  // tilt 0 at the end
    std::printf("  corner %d: start local (%+.3f, %+.3f, %+.3f), final local (%+.3f, %+.3f, %+.3f)\n", k, start.x(),
                start.y(), start.z(), l.x(), l.y(), l.z());
    EXPECT_LT(start.x() * l.x(), 0.0) << k;
    EXPECT_NEAR(l.y(), 0.0, 0.012) << k;
    EXPECT_LT(std::hypot(l.x(), l.z()), env.flip_config().pan.flat_radius) << k;
  }
  // the flip is not a knife edge: small perturbations of the params still flip
  Rng rng(7);
  int flipped = 0;
  const int tries = 8;
  for (int t = 0; t < tries; ++t) {
    auto y = x;
    for (auto& v : y) v = std::clamp(v + rng.uniform(-0.02, 0.02), -1.0, 1.0);
    flipped += env.orientation(env.final_state(y), env.waypoints(y)[5]) < -0.9 && env.loss(y) < 0.03;
  }
  std::printf("flip example: %d of %d perturbations (+-0.02 per param) still flip\n", flipped, tries);
  EXPECT_GE(flipped, tries - 1);
  // and the gradient there is finite
  std::vector<double> g(15);
  EXPECT_EQ(env.loss_and_grad(x, g), loss);
  for (double v : g) EXPECT_TRUE(std::isfinite(v));
}

TEST(FlipTask, OptimizersFindFlips) {
  // best points of `harness --env flip --optimizer cmaes,gd --seeds 2 --budget 400` (seed 0 each):
  // both are flips (face down on the pan, corners mirrored), not another shape with a small corner
  // loss; the gd one ends with the pan tilted 0.52 rad and the pancake lying flipped on it
  const auto& env = flip();
  const std::vector<std::vector<double>> found = {
      {0.0826852570292331, 0.5864021882931569, 0.6972782255715837, -0.08401210799451772, -0.7678927824066717,
       0.11661480807384463, -0.13822987319334643, -0.4537552744753175, -0.04861537430354457, -0.31680686979336115,
       -0.5361731565476271, 0.15618417297573972, -0.5648945724698907, -0.45543862400200513, -0.074206140514305},
      {-0.1439717550652901, -0.9383253828096987, 0.1770771284444867, 0.1138864141968489, 0.8268381994932765,
       -0.20266292182257703, 0.32029840282242605, -0.9729964087359793, 0.36714012735346313, -0.10609258999779832,
       -0.26910589148036235, -0.07187187210170598, 0.2969766131357707, 0.5579902995763354, 0.4324301431933898}};
  for (const auto& x : found) {
    const double loss = env.loss(x);
    const double orientation = env.orientation(env.final_state(x), env.waypoints(x)[5]);
    std::printf("optimizer-found flip: loss %.6f m, orientation %.4f\n", loss, orientation);
    EXPECT_LT(loss, 1e-3);
    EXPECT_LT(orientation, -0.99);
  }
}

using testing::smooth_at;

TEST(FlipGradient, MatchesCentralDifferencesAwayFromContactSwitches) {
  // seeded points in [-0.4, 0.4]^15 (the pancake tossed about, landing in the pan or not); points
  // whose difference window crosses a contact switch (a vertex touches or leaves the pan one step
  // earlier or later: the loss jumps there, see AcrossAContactSwitch...) are skipped and counted
  GradientCheckOptions options;
  options.step = 1e-7;
  options.tolerance = 1e-4;
  options.relative_floor = 1e-3;
  const auto& env = flip();
  Rng rng(1115);
  int accepted = 0, skipped = 0;
  double worst = 0.0;
  while (accepted < 3 && skipped < 20) {
    std::vector<double> x(15);
    for (auto& v : x) v = rng.uniform(-0.4, 0.4);
    if (!smooth_at(env, x, options.step)) {
      ++skipped;
      continue;
    }
    ++accepted;
    const auto r = check_gradient(env, x, options);
    EXPECT_TRUE(r.value_agrees);
    EXPECT_GT(r.max_abs_central, 1e-4) << "degenerate point";
    EXPECT_TRUE(r.passed) << "worst coordinate " << r.worst_coordinate << " relative error " << r.worst_relative_error
                          << " analytic " << r.coordinates[r.worst_coordinate].analytic << " central "
                          << r.coordinates[r.worst_coordinate].differences.central;
    worst = std::max(worst, r.worst_relative_error);
    std::printf("  point %d: loss %.5f, |grad| %.3e, worst relative error %.2e\n", accepted, r.loss, r.gradient_norm,
                r.worst_relative_error);
  }
  std::printf(
      "flip: gradient vs central differences (h 1e-7) at %d points, worst relative error %.2e; %d points skipped "
      "(contact switch within +-h)\n",
      accepted, worst, skipped);
  EXPECT_EQ(accepted, 3);
}

TEST(FlipGradient, AcrossAContactSwitchTheLossJumpsAndTheGradientIsOneSided) {
  // Along the toss height (x[4]) from the pinned flip, bisect to where the per-step contact pattern
  // first changes. The contact acts when a vertex starts a step at or inside the pan and moves into
  // it, so a switch is a vertex meeting (or leaving) the pan one step earlier or later. A vertex
  // that meets the pan at speed one step later keeps its inward velocity one step longer: the
  // trajectory, and the loss, jump (here by 8.5e-6 m over a bracket of 1e-13, where the slope
  // accounts for 7e-14; a grazing contact, inward speed about 0 at the switch, would leave the loss
  // continuous). The analytic gradient is the derivative of the piece it is evaluated in (finite,
  // blind to the switch) and agrees with the one-sided difference inside that piece.
  const auto r = testing::across_contact_switch(flip(), flip().flip_config().flip_example, 4, 1e-4, 1e-9);
  ASSERT_TRUE(r.found) << "no switch within 1e-4, or the left window leaves the piece";
  EXPECT_TRUE(r.gradient_finite);
  std::printf(
      "contact switch at toss-height param %.15f: loss change over %.1e: %.3e m (slope x width %.3e), left difference "
      "%.6e, analytic %.6e\n",
      r.at, r.bracket, r.jump, r.left_difference * r.bracket, r.left_difference, r.analytic);
  EXPECT_NEAR(r.analytic, r.left_difference, 1e-3 * std::abs(r.left_difference) + 1e-4);
  // the jump is far larger than the slope times the bracket width
  EXPECT_GT(std::abs(r.jump), 1e3 * (std::abs(r.left_difference) + 1.0) * r.bracket);
}

TEST(FlipDeterminism, RerunsAreBitIdentical) {
  const auto& env = flip();
  Rng rng(3);
  std::vector<double> x(15);
  for (auto& v : x) v = rng.uniform(-1.0, 1.0);
  auto ws = env.make_workspace();
  std::vector<double> losses, g1(15), g2(15), g3(15);
  losses.push_back(env.loss_and_grad(x, g1, *ws, serial_team()));
  losses.push_back(env.loss(x, *ws, serial_team()));
  losses.push_back(env.loss_and_grad(x, g2, *ws, serial_team()));
  losses.push_back(env.loss_and_grad(x, g3));   // fresh workspace
  losses.push_back(make_env("flip")->loss(x));  // fresh env and model
  for (double l : losses) EXPECT_EQ(l, losses[0]);
  EXPECT_TRUE(std::isfinite(losses[0]));
  EXPECT_EQ(g1, g2);
  EXPECT_EQ(g1, g3);
}

TEST(FlipNames, BadNamesAreRefused) {
  for (const std::string bad : {"flip-", "flip-2", "flip_x"}) EXPECT_THROW(make_env(bad), UsageError) << bad;
  EXPECT_THROW(make_env("flipx"), UsageError);  // no family knows it
  EXPECT_NO_THROW(make_env("flip"));
  const auto names = grid_env_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "flip"), names.end());
  // making an env, its info and its config build no model
  const std::int64_t before = lazy_model_builds();
  const auto env = make_env("flip");
  EXPECT_TRUE(env->differentiable());
  EXPECT_TRUE(env->supports_rl());
  (void)env->config();
  EXPECT_EQ(lazy_model_builds(), before);
}

TEST(FlipRl, ReplayingParamsGivesTheLossAndObservationsAreSane) {
  const auto& env = flip();
  auto rl = env.make_rl();
  ASSERT_TRUE(rl);
  EXPECT_EQ(rl->observation_dim(), 61);
  EXPECT_EQ(rl->action_dim(), 3);
  EXPECT_EQ(rl->horizon(), 50);
  auto o = rl->observe();
  ASSERT_EQ(o.size(), 61u);
  EXPECT_EQ(o[54], 0.0);  // pan pose
  EXPECT_EQ(o[60], 0.0);  // time
  // replay: the pinned flip and two seeded vectors; the pose path is the same chord by chord,
  // summed in another order (rounding differences only)
  Rng rng(11);
  std::vector<std::vector<double>> xs = {env.flip_config().flip_example, std::vector<double>(15),
                                         std::vector<double>(15)};
  for (auto& v : xs[1]) v = rng.uniform(-0.5, 0.5);
  for (auto& v : xs[2]) v = rng.uniform(-1.0, 1.0);
  for (const auto& x : xs) {
    const auto actions = env.rl_actions(x);
    ASSERT_EQ(actions.size(), 150u);
    for (double a : actions) EXPECT_LE(std::abs(a), 1.0 + 1e-12);
    rl->reset();
    int j = 0;
    while (!rl->done()) {
      rl->step(std::span<const double>(actions.data() + 3 * j, 3));
      ++j;
    }
    EXPECT_EQ(j, 50);
    const double direct = env.loss(x), replay = rl->final_loss();
    std::printf("rl replay: loss() %.12f, RL view %.12f (difference %.2e)\n", direct, replay, replay - direct);
    EXPECT_NEAR(replay, direct, 1e-9 * std::max(1.0, std::abs(direct)));
  }
  // the final observation: the pan's pose is waypoint 5, time 1
  o = rl->observe();
  const auto w = env.waypoints(xs[2]);
  EXPECT_NEAR(o[54], w[5].x, 1e-12);
  EXPECT_NEAR(o[56], w[5].tilt, 1e-12);
  EXPECT_EQ(o[60], 1.0);
  // actions beyond [-1, 1] are clamped
  rl->reset();
  const double big[3] = {5.0, -5.0, 0.0};
  rl->step(big);
  o = rl->observe();
  const auto step = env.max_step();
  EXPECT_NEAR(o[54], step[0], 1e-15);
  EXPECT_NEAR(o[55], -step[1], 1e-15);
}

TEST(FlipTiming, ForwardAndGradientEpisodes) {
  // informational: ms per episode on this machine (no assertion)
  const auto& env = flip();
  auto ws = env.make_workspace();
  const auto& x = env.flip_config().flip_example;
  std::vector<double> g(15);
  using clock = std::chrono::steady_clock;
  const int reps = 5;
  env.loss(x, *ws, serial_team());
  auto t0 = clock::now();
  for (int r = 0; r < reps; ++r) env.loss(x, *ws, serial_team());
  const double fwd = std::chrono::duration<double, std::milli>(clock::now() - t0).count() / reps;
  env.loss_and_grad(x, g, *ws, serial_team());
  t0 = clock::now();
  for (int r = 0; r < reps; ++r) env.loss_and_grad(x, g, *ws, serial_team());
  const double grad = std::chrono::duration<double, std::milli>(clock::now() - t0).count() / reps;
  std::printf("flip: forward %.2f ms, gradient %.2f ms per episode (ratio %.2f)\n", fwd, grad, grad / fwd);
}

class FlipHarness : public dsb::testing::TempDirTest {};

TEST_F(FlipHarness, ListEvalBadNameAndGd) {
  auto r = testing::run_harness(dir_, "list");
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("flip"), std::string::npos) << r.out;

  std::string xs;
  for (double v : flip().flip_config().flip_example) xs.append(xs.empty() ? "" : ",").append(std::to_string(v));
  r = testing::run_harness(dir_, "eval --env flip --x " + xs + " --grad");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_LT(j["loss"].get<double>(), 0.01);
  ASSERT_EQ(j["grad"].size(), 15u);

  r = testing::run_harness(dir_, "eval --env flip-x --x 0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("flip-x"), std::string::npos) << r.err;

  const std::string db = (dir_ / "flip.sqlite").string();
  r = testing::run_harness(dir_, "--env flip --optimizer gd --seeds 1 --budget 3 --quiet --db " + db);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto n = testing::episode_counts(db);
  EXPECT_EQ(n.episodes, 3);
  EXPECT_EQ(n.finite, 3) << "every episode finite";
  EXPECT_EQ(n.matching, 3) << "gd's episodes carry gradients";
}

}  // namespace
}  // namespace dsb
