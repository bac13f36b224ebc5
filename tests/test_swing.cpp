// The six `swing-*` tasks (envs/cloth/swing_*): config facts (stability over the stiffness range,
// patches, validation), the scripted swing really throws the cloth onto the floor, loss 0 at the
// reference params, gradients vs central differences at seeded points away from contact switches
// and what happens across one, identical reruns, bad names, the harness end to end, and the
// forward / gradient episode times (printed, not asserted).
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
#include "envs/cloth/swing_env.hpp"
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
using cloth::SwingEnv;

const std::vector<std::string> kTasks = {"swing-stiffness-single", "swing-stiffness-corner", "swing-stiffness-mesh",
                                         "swing-velocity-single",  "swing-velocity-corner",  "swing-velocity-mesh"};

const SwingEnv& swing(const std::string& name) { return dynamic_cast<const SwingEnv&>(*shared_env(name)); }

TEST(SwingConfig, DefaultsAreValidAndStoredWithTheRun) {
  const cloth::SwingConfig cfg;
  EXPECT_NO_THROW(cfg.validate());
  EXPECT_EQ(cfg.steps(), 1600);
  EXPECT_EQ(cfg.release_step(), 600);
  const auto j = swing("swing-stiffness-mesh").config();
  EXPECT_EQ(j["steps"], 1600);
  EXPECT_EQ(j["k_low"], 10.0);
  EXPECT_EQ(j["k_high"], 60.0);
  EXPECT_EQ(j["stiffness_reference"].size(), 16u);
  EXPECT_NE(j.dump(), swing("swing-velocity-mesh").config().dump());  // params and loss differ
  EXPECT_NE(j.dump(), swing("swing-stiffness-corner").config().dump());
}

TEST(SwingConfig, InvalidFieldsAreNamed) {
  auto expect_field = [](const cloth::SwingConfig& c, const std::string& field) {
    testing::expect_config_error_naming(c, field);
  };
  cloth::SwingConfig c;
  c.k_low = 100.0;
  expect_field(c, "k_high");
  c = {};
  c.dt = 0.0;
  expect_field(c, "dt");
  c = {};
  c.release_time = 5.0;
  expect_field(c, "release_time");
  c = {};
  c.stiffness_reference.pop_back();
  expect_field(c, "stiffness_reference");
  c = {};
  c.velocity_reference[1] = 1.5;
  expect_field(c, "velocity_reference");
  c = {};
  c.cols = 3;
  expect_field(c, "cols");
  c = {};
  c.tangential_keep = 2.0;
  expect_field(c, "tangential_keep");
}

TEST(SwingModel, StableOverTheStiffnessRangeAndPatchesCoverTheCloth) {
  const auto& env = swing("swing-stiffness-single");
  const auto& m = env.model();
  const auto& cfg = env.swing_config();
  EXPECT_EQ(env.dim(), 16);
  EXPECT_EQ(swing("swing-velocity-corner").dim(), 3);
  EXPECT_EQ(m.cloth.vertices(), 81);
  // symplectic Euler needs omega dt < 2: the Gershgorin bound with every patch at k_high
  const double hi = cloth::frequency_bound(m.cloth, env.stiffness(std::vector<double>(16, 1.0))) * cfg.dt;
  const double lo = cloth::frequency_bound(m.cloth, env.stiffness(std::vector<double>(16, -1.0))) * cfg.dt;
  std::printf("frequency_bound * dt: %.3f at k_high, %.3f at k_low\n", hi, lo);
  EXPECT_LT(hi, 1.0);
  // the stiffness map's ends and middle
  const auto k = env.stiffness(std::vector<double>(16, -1.0));
  for (std::size_t s = 0; s < k.size(); ++s) {
    const double ratio = m.spring_ratio[s];
    EXPECT_NEAR(k[s], ratio * cfg.k_low, 1e-12 * cfg.k_low);
  }
  EXPECT_NEAR(m.fixed_stiffness[0], std::sqrt(cfg.k_low * cfg.k_high), 1e-12);
  // every patch holds springs, the same number for the 4 inner and for the edge patches by symmetry
  std::vector<int> count(16, 0);
  for (int p : m.spring_patch) {
    ASSERT_GE(p, 0);
    ASSERT_LT(p, 16);
    ++count[p];
  }
  for (int p = 0; p < 16; ++p) EXPECT_GT(count[p], 10) << "patch " << p;
  EXPECT_EQ(count[5], count[6]);
  EXPECT_EQ(count[5], count[9]);
  EXPECT_EQ(count[5], count[10]);
  // the held corners are the front edge's
  ASSERT_EQ(m.cloth.anchors.size(), 2u);
  EXPECT_EQ(m.cloth.rest_position[m.cloth.anchors[0].vertex].z(), 0.0);
  EXPECT_NEAR(
      m.cloth.rest_position[m.cloth.anchors[1].vertex].x() - m.cloth.rest_position[m.cloth.anchors[0].vertex].x(), 0.2,
      1e-12);
}

TEST(SwingModel, TheSwingThrowsTheClothOntoTheFloor) {
  // at the reference params (and the box's corners) the cloth is released and lies on the floor
  // at the end, forward of where it started
  for (const std::string name : {"swing-stiffness-mesh", "swing-velocity-mesh"}) {
    const auto& env = swing(name);
    for (const double corner : {-1.0, 0.0, 1.0}) {
      std::vector<double> x = corner == 0.0 ? env.reference() : std::vector<double>(env.dim(), corner);
      const auto s = env.final_state(x);
      double lowest = 1e9, highest = -1e9, y = 0.0, z = 0.0;
      for (const auto& p : s.x) {
        lowest = std::min(lowest, p.y());
        highest = std::max(highest, p.y());
        y += p.y() / s.x.size();
        z += p.z() / s.x.size();
      }
      const auto pattern = env.contact_pattern(x);
      const long contacts = std::count(pattern.begin(), pattern.end(), 1);
      std::printf("%s x = %s: final heights [%.4f, %.4f] m (mean %.4f), mean z %.3f m, %ld contact vertex-steps\n",
                  name.c_str(),
                  corner == 0.0    ? "reference"
                      : corner < 0 ? "-1"
                                   : "+1",
                  lowest, highest, y, z, contacts);
      EXPECT_GT(lowest, -0.01);  // no vertex far into the floor (one step's travel at most)
      EXPECT_LT(y, 0.02);        // lying on the floor (no self-collision: a fold may stand up a little)
      EXPECT_LT(highest, 0.1);
      EXPECT_GT(z, 0.05);  // thrown forward: the cloth started at mean z = -0.1
      EXPECT_GT(contacts, 1000);
    }
  }
}

TEST(SwingModel, StretchDuringTheSwingStaysModest) {
  // largest structural-spring strain (l - L0) / L0 over the held part of the episode (steps before
  // the release), with every patch at k_low, the middle and k_high
  const auto& env = swing("swing-stiffness-single");
  const auto& m = env.model();
  const int release = env.swing_config().release_step();
  for (const double x : {-1.0, 0.0, 1.0}) {
    const std::vector<double> p(16, x);
    const auto k = env.stiffness(p);
    cloth::ClothTape tape;
    cloth::cloth_rollout(m.cloth, cloth::ClothInputs{k, m.anchor_path}, env.initial_state(p), release, tape);
    double worst = 0.0;
    for (int t = 0; t <= release; ++t) {
      const auto xt = tape.x(t);
      for (const auto& sp : m.cloth.springs)
        if (sp.kind == cloth::SpringKind::structural)
          worst = std::max(worst, ((xt[sp.j] - xt[sp.i]).norm() - sp.rest_length) / sp.rest_length);
    }
    std::printf("every patch at x = %+.0f (k = %.1f N/m): largest structural strain while held %.3f\n", x, k[0], worst);
    EXPECT_LT(worst,
              0.6);  // measured 0.56, 0.27, 0.15: a stretchy cloth at the soft end (docs/engine-cloth.md "swing")
  }
}

TEST(SwingLoss, ZeroAtTheReferenceParamsOnAllSix) {
  for (const auto& name : kTasks) {
    const auto& env = swing(name);
    const auto ref = env.reference();
    std::vector<double> grad(env.dim());
    EXPECT_EQ(env.loss(ref), 0.0) << name;
    EXPECT_EQ(env.loss_and_grad(ref, grad), 0.0) << name;
    for (double g : grad) EXPECT_TRUE(std::isfinite(g)) << name;
    // and clearly not zero elsewhere
    const double off = env.loss(std::vector<double>(env.dim(), 0.5));
    std::printf("%s: loss at reference %.3g, at x = 0.5 %.4f m\n", name.c_str(), env.loss(ref), off);
    EXPECT_GT(off, 1e-3) << name;
  }
}

using testing::smooth_at;

TEST(SwingGradient, MatchesCentralDifferencesAwayFromContactSwitches) {
  // 3 seeded points per task in [-0.8, 0.8]^d. Points whose difference window crosses a contact
  // switch (a vertex lands or lifts off one step earlier or later: the loss jumps by O(dt |v|)
  // there, see AcrossAContactSwitch...) are skipped and counted.
  GradientCheckOptions options;
  options.step = 1e-7;
  options.tolerance = 1e-4;
  options.relative_floor = 1e-3;
  for (const auto& name : kTasks) {
    const auto& env = swing(name);
    Rng rng(1000 + env.dim());
    int accepted = 0, skipped = 0;
    double worst = 0.0;
    while (accepted < 3 && skipped < 12) {
      std::vector<double> x(env.dim());
      for (auto& v : x) v = rng.uniform(-0.8, 0.8);
      if (!smooth_at(env, x, options.step)) {
        ++skipped;
        continue;
      }
      ++accepted;
      const auto r = check_gradient(env, x, options);
      EXPECT_TRUE(r.value_agrees) << name;
      EXPECT_GT(r.max_abs_central, 1e-4) << name << ": degenerate point";
      EXPECT_TRUE(r.passed) << name << ": worst coordinate " << r.worst_coordinate << " relative error "
                            << r.worst_relative_error << " analytic " << r.coordinates[r.worst_coordinate].analytic
                            << " central " << r.coordinates[r.worst_coordinate].differences.central;
      worst = std::max(worst, r.worst_relative_error);
    }
    std::printf(
        "%s: gradient vs central differences (h 1e-7) at %d points, worst relative error %.2e; %d points "
        "skipped (contact switch within +-h)\n",
        name.c_str(), accepted, worst, skipped);
    EXPECT_EQ(accepted, 3) << name;
  }
}

TEST(SwingGradient, AcrossAContactSwitchTheLossJumpsAndTheGradientIsOneSided) {
  // Along vz (x[2]) of swing-velocity-mesh, bisect to where the per-step contact pattern changes.
  // The projection contact is tested at the step's start position, so a vertex that reaches the
  // floor one step later keeps its inward velocity one step longer: the trajectory, and the loss,
  // jump. The analytic gradient is the derivative of the piece it is evaluated in (finite, blind to
  // the switch) and agrees with the one-sided difference that stays inside that piece.
  const auto r = testing::across_contact_switch(swing("swing-velocity-mesh"), {0.1, -0.2, 0.0}, 2, 1e-3, 1e-8);
  ASSERT_TRUE(r.found) << "no switch within 1e-3, or the left window leaves the piece";
  EXPECT_TRUE(r.gradient_finite);
  std::printf("contact switch at vz param %.15f: loss change over %.1e %.3e m, left difference %.6e, analytic %.6e\n",
              r.at, r.bracket, r.jump, r.left_difference, r.analytic);
  EXPECT_NEAR(r.analytic, r.left_difference, 1e-3 * std::abs(r.left_difference) + 1e-5);
  // the jump is far larger than the slope times the bracket width
  EXPECT_GT(std::abs(r.jump), 1e3 * (std::abs(r.left_difference) + 1.0) * r.bracket);
}

TEST(SwingDeterminism, RerunsAreBitIdentical) {
  for (const std::string name : {"swing-stiffness-corner", "swing-velocity-single"}) {
    const auto& env = swing(name);
    Rng rng(3);
    std::vector<double> x(env.dim());
    for (auto& v : x) v = rng.uniform(-1.0, 1.0);
    auto ws = env.make_workspace();
    std::vector<double> losses, g1(env.dim()), g2(env.dim()), g3(env.dim());
    losses.push_back(env.loss_and_grad(x, g1, *ws, serial_team()));
    losses.push_back(env.loss(x, *ws, serial_team()));
    losses.push_back(env.loss_and_grad(x, g2, *ws, serial_team()));
    losses.push_back(env.loss_and_grad(x, g3));  // fresh workspace
    losses.push_back(make_env(name)->loss(x));   // fresh env and model
    for (double l : losses) EXPECT_EQ(l, losses[0]) << name;
    EXPECT_EQ(g1, g2) << name;
    EXPECT_EQ(g1, g3) << name;
  }
}

TEST(SwingNames, BadNamesAreRefused) {
  for (const std::string bad : {"swing-stiffness", "swing-foo-single", "swing-velocity-meshy", "swing-", "swing"})
    EXPECT_THROW(make_env(bad), UsageError) << bad;
  for (const auto& name : kTasks) EXPECT_NO_THROW(make_env(name));
  const auto names = grid_env_names();
  for (const auto& name : kTasks) EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  // making an env, its info and its config build no model (the reference episode runs lazily)
  const std::int64_t before = lazy_model_builds();
  for (const auto& name : kTasks) {
    const auto env = make_env(name);
    EXPECT_TRUE(env->differentiable());
    EXPECT_TRUE(env->supports_rl());
    (void)env->config();
  }
  EXPECT_EQ(lazy_model_builds(), before);
}

TEST(SwingRl, OneActionRunsTheEpisodeWithTheLossOfLoss) {
  Rng rng(31);
  for (const std::string name : {"swing-stiffness-corner", "swing-velocity-single"}) {
    const auto base = make_env(name);
    const auto& env = static_cast<const SwingEnv&>(*base);
    const auto rl = env.make_rl();
    ASSERT_TRUE(rl);
    EXPECT_EQ(rl->observation_dim(), 61);
    EXPECT_EQ(rl->action_dim(), env.dim());
    EXPECT_EQ(rl->horizon(), 1);
    const auto& m = env.model();
    // before the action: the cloth at rest, the held corners at their start, time 0
    auto o = rl->observe();
    ASSERT_EQ(o.size(), 61u);
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(o[3 * k + c], m.cloth.rest_position[m.observed[k]](c));
        EXPECT_EQ(o[27 + 3 * k + c], 0.0);
      }
    EXPECT_EQ(o[54], m.anchor_path[0].x());
    EXPECT_EQ(o[60], 0.0);
    for (int trial = 0; trial < 3; ++trial) {
      std::vector<double> x(env.dim());
      for (double& v : x) v = rng.uniform(-1.0, 1.0);
      rl->reset();
      EXPECT_FALSE(rl->done());
      rl->step(x);
      ASSERT_TRUE(rl->done());
      // the same number as loss(), bit for bit, and the observation is the final state's
      EXPECT_EQ(rl->final_loss(), env.loss(x)) << name;
      const auto final_state = env.final_state(x);
      o = rl->observe();
      for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) {
          EXPECT_EQ(o[3 * k + c], final_state.x[m.observed[k]](c));
          EXPECT_EQ(o[27 + 3 * k + c], final_state.v[m.observed[k]](c));
        }
      EXPECT_EQ(o[60], 1.0);
      // a step after done changes nothing
      const std::vector<double> other(env.dim(), 0.9);
      rl->step(other);
      EXPECT_EQ(rl->final_loss(), env.loss(x));
    }
    // actions outside [-1, 1] are clamped to the box
    std::vector<double> wild(env.dim(), 3.0), edge(env.dim(), 1.0);
    rl->reset();
    rl->step(wild);
    EXPECT_EQ(rl->final_loss(), env.loss(edge)) << name;
  }
}

TEST(SwingTiming, ForwardAndGradientEpisodes) {
  // informational: ms per episode on this machine (no assertion)
  for (const auto& name : kTasks) {
    const auto& env = swing(name);
    auto ws = env.make_workspace();
    std::vector<double> x(env.dim(), 0.3), g(env.dim());
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
    std::printf("%s: forward %.2f ms, gradient %.2f ms per episode (ratio %.2f)\n", name.c_str(), fwd, grad,
                grad / fwd);
  }
}

class SwingHarness : public dsb::testing::TempDirTest {};

TEST_F(SwingHarness, ListEvalBadNameAndGdOnAllSix) {
  auto r = testing::run_harness(dir_, "list");
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("swing-stiffness-mesh"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("swing-velocity-single"), std::string::npos) << r.out;

  r = testing::run_harness(dir_, "eval --env swing-velocity-corner --x 0.2,0.4,-0.3 --grad");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["loss"].get<double>(), 0.0);  // the reference params
  ASSERT_EQ(j["grad"].size(), 3u);

  r = testing::run_harness(dir_, "eval --env swing-velocity-cornerx --x 0,0,0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("swing-velocity-cornerx"), std::string::npos) << r.err;

  std::string envs;
  for (const auto& name : kTasks) envs += (envs.empty() ? "" : ",") + name;
  const std::string db = (dir_ / "swing.sqlite").string();
  r = testing::run_harness(dir_, "--env " + envs + " --optimizer gd --seeds 1 --budget 3 --quiet --db " + db);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto n = testing::episode_counts(db);
  EXPECT_EQ(n.episodes, 18);
  EXPECT_EQ(n.finite, 18) << "every episode finite";
  EXPECT_EQ(n.matching, 18) << "gd's episodes carry gradients";
}

}  // namespace
}  // namespace dsb
