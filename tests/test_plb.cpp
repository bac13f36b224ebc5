// The PlasticineLab tasks (envs/mpm/plb_*): models as the facts give them, gradients against
// central differences at a short horizon, targets with PlasticineLab's figures, the loss measuring
// the task, the RL view, the second metric, and the harness running them.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/mpm/target_shape.hpp"
#include "envs/registry.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using mpm::Vec3;

const mpm::PlbEnv& plb(const std::string& name) { return static_cast<const mpm::PlbEnv&>(*shared_env(name)); }

struct Expected {
  const char* task;
  int dim, particles;
  double E, nu, yield, floor_friction;
};

// PlasticineLab's task files
const Expected kExpected[] = {{"assembly", 30, 10000, 5e3, 0.2, 100, 100},  {"pinch", 15, 6000, 5e3, 0.2, 50, 100},
                              {"rollingpin", 15, 10000, 5e3, 0.2, 50, 1.5}, {"rope", 30, 10000, 5e3, 0.2, 50, 0.3},
                              {"table", 15, 10000, 5e3, 0.05, 50, 0.3},     {"torus", 15, 10000, 5e3, 0.2, 50, 100},
                              {"triplemove", 90, 9999, 5e3, 0.2, 200, 1.5}, {"writer", 15, 10000, 5e3, 0.2, 50, 100}};

TEST(Plb, ModelsAsPlasticineLabDefinesThem) {
  EXPECT_EQ(mpm::plb_tasks().size(), 8u);
  for (const auto& e : kExpected) {
    SCOPED_TRACE(e.task);
    const auto& env = plb(std::string("plb-") + e.task);
    EXPECT_EQ(env.dim(), e.dim);
    const auto& m = env.model().mpm;
    EXPECT_EQ(m.particles(), e.particles);
    // p_mass = p_vol x p_rho = (dx / 2)^2 x 1
    for (double mass : m.mass) ASSERT_DOUBLE_EQ(mass, 0.5 / 64 * 0.5 / 64);
    const auto& mat = m.materials[0];
    EXPECT_EQ(mat.youngs_modulus, e.E);
    EXPECT_EQ(mat.poisson_ratio, e.nu);
    EXPECT_EQ(mat.yield_stress, e.yield);
    EXPECT_EQ(m.config.floor_friction, e.floor_friction);
    // PlasticineLab's simulator: 64^3, dt 1e-4, 19 substeps, gravity 30, 3-cell walls
    EXPECT_EQ(m.config.grid, (std::array<int, 3>{64, 64, 64}));
    EXPECT_EQ(m.config.dt, 1e-4);
    EXPECT_EQ(m.config.substeps, 19);
    EXPECT_EQ(m.config.gravity, Vec3(0, -30, 0));
    EXPECT_EQ(m.config.bound, 3);
    for (const auto& p : m.primitives) EXPECT_EQ(p.softness, 666.0) << p.name;
    // every particle inside its shapes' union (boxes and balls of the table)
    const auto& task = *mpm::find_plb_task(e.task);
    for (const auto& p : m.initial) {
      bool inside = false;
      for (const auto& s : task.shapes)
        inside = inside ||
            (s.kind == mpm::PlbShape::Kind::box
                 ? ((p.x - s.centre).cwiseAbs().array() <= s.size.array() / 2 + 1e-12).all()
                 : (p.x - s.centre).norm() <= s.radius + 1e-12);
      ASSERT_TRUE(inside);
    }
  }
  // primitives, poses, bounds and action scales of a few tasks, from the facts' table
  const auto& rp = plb("plb-rollingpin").model().mpm.primitives[0];
  EXPECT_EQ(rp.motion, mpm::PrimitiveMotion::rolling_pin);
  EXPECT_EQ(rp.shape.half_height, 0.15);
  EXPECT_EQ(rp.shape.radius, 0.03);
  EXPECT_EQ(rp.position, Vec3(0.5, 0.123, 0.5));
  EXPECT_EQ(rp.action_scale, (std::vector<double>{0.6667, 0.0667, 0.001}));
  const auto& pinch = plb("plb-pinch").model().mpm.primitives[0];
  EXPECT_EQ(pinch.lower_bound, Vec3::Constant(0.1));
  EXPECT_EQ(pinch.upper_bound, Vec3::Constant(0.9));
  const auto& rope = plb("plb-rope").model().mpm.primitives;
  ASSERT_EQ(rope.size(), 3u);
  EXPECT_EQ(rope[2].action_dim(), 0) << "the pillar is static";
  EXPECT_EQ(rope[2].shape.kind, mpm::ShapeKind::cylinder);
  EXPECT_EQ(rope[2].position, Vec3(0.3919, 0.0, 0.4991));
  const auto& writer = plb("plb-writer").model().mpm.primitives[0];
  EXPECT_EQ(writer.friction, 0.0);
  EXPECT_EQ(writer.lower_bound.y(), 0.05);
  EXPECT_EQ(plb("plb-table").model().mpm.primitives[0].action_scale, (std::vector<double>{0.03, 0.0, 0.03}));
  EXPECT_EQ(plb("plb-triplemove").model().mpm.primitives.size(), 6u);
}

TEST(Plb, GradientsMatchCentralDifferencesOnEveryTask) {
  // 5 env steps (95 substeps). PlasticineLab's contact switches on with a jump (influence 0.1) and
  // friction and plasticity have kinks, so the window must stay small (measured on rollingpin: a
  // window of 2e-6 crosses a switch, 2e-7 does not) and differences then carry ~5e-8 of rounding
  // noise on a loss of ~25 summed over 66^3 nodes: we accept |analytic - central| <= 1e-6 +
  // 1e-4 |central| (the relative error's floor 1e-2 x the tolerance 1e-4)
  GradientCheckOptions options;
  options.step = 1e-7;
  options.tolerance = 1e-4;
  options.absolute_floor = 1e-2;
  for (const auto& t : mpm::plb_tasks()) {
    const auto& env = plb("plb-" + t.name + "-h5");
    Rng rng(fnv1a64(t.name));
    std::vector<double> x(env.dim());
    for (auto& v : x) v = rng.uniform(-1.0, 1.0);
    const auto r = check_gradient(env, x, options);
    std::printf("  %-11s |grad| %.3e, worst absolute error %.2e, worst relative error %.2e\n", t.name.c_str(),
                r.gradient_norm, r.worst_absolute_error, r.worst_relative_error);
    EXPECT_TRUE(r.value_agrees) << t.name;
    EXPECT_GT(r.max_abs_central, 1e-4) << t.name << ": the actions move something";
    EXPECT_TRUE(r.passed) << t.name << ": worst coordinate " << r.worst_coordinate << ", relative error "
                          << r.worst_relative_error;
  }
}

TEST(Plb, TargetsHavePlasticineLabsFigures) {
  // every generated target (data/targets) against the figures of PlasticineLab's v1 target
  // (target_shape.hpp: cells above 1% of the grid's maximum, face-connected bodies): as many
  // bodies, each within 0.01 of its PlasticineLab body's centre of mass (a single body: the whole
  // target's) and its bounding box within one cell (1/64) on every face (plus 5e-4: the facts
  // round to 3 decimals); the mass of 10,000 particles, as every PlasticineLab target has it
  const double dx = 1.0 / 64, p_mass = 0.5 / 64 * 0.5 / 64;
  const auto cells = [dx](double d) { return std::lround(d / dx); };
  for (const auto& t : mpm::plb_tasks()) {
    SCOPED_TRACE(t.name);
    const auto& model = plb("plb-" + t.name).model();
    const mpm::TargetShape s = mpm::describe_target_shape(model.target, model.mpm.config.pad, model.mpm.config.dx);
    EXPECT_NEAR(s.mass, mpm::kPlbTargetParticles * p_mass, 1e-12);
    ASSERT_EQ(s.bodies.size(), t.plb_target.size()) << "connected bodies";
    std::vector<bool> matched(s.bodies.size(), false);
    for (const auto& theirs : t.plb_target) {
      // ours: the body whose centre is nearest
      std::size_t best = 0;
      for (std::size_t b = 1; b < s.bodies.size(); ++b)
        if ((s.bodies[b].centre - theirs.centre).norm() < (s.bodies[best].centre - theirs.centre).norm()) best = b;
      EXPECT_FALSE(matched[best]) << "two of PlasticineLab's bodies are nearest to one of ours";
      matched[best] = true;
      const auto& ours = s.bodies[best];
      const Vec3 centre = t.plb_target.size() == 1 ? s.centre : ours.centre;
      std::printf(
          "  %-11s centre (%.3f, %.3f, %.3f) vs (%.3f, %.3f, %.3f): %.4f apart; box faces off by "
          "(%+ld %+ld %+ld)..(%+ld %+ld %+ld) cells\n",
          t.name.c_str(), centre.x(), centre.y(), centre.z(), theirs.centre.x(), theirs.centre.y(), theirs.centre.z(),
          (centre - theirs.centre).norm(), cells(ours.lo.x() - theirs.lo.x()), cells(ours.lo.y() - theirs.lo.y()),
          cells(ours.lo.z() - theirs.lo.z()), cells(ours.hi.x() - theirs.hi.x()), cells(ours.hi.y() - theirs.hi.y()),
          cells(ours.hi.z() - theirs.hi.z()));
      EXPECT_LE((centre - theirs.centre).norm(), 0.01);
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(ours.lo[a], theirs.lo[a], dx + 5e-4) << "lower face, axis " << a;
        EXPECT_NEAR(ours.hi[a], theirs.hi[a], dx + 5e-4) << "upper face, axis " << a;
      }
    }
  }
}

TEST(Plb, RlViewReplaysTheEpisodeAndTheMetricIsTheFinalSoftIou) {
  const auto& env = plb("plb-pinch-h5");
  auto rl = env.make_rl();
  ASSERT_TRUE(rl);
  EXPECT_EQ(rl->action_dim(), 3);
  EXPECT_EQ(rl->observation_dim(), 200 * 6 + 7);
  EXPECT_EQ(rl->horizon(), 5);
  Rng rng(3);
  std::vector<double> x(env.dim());
  for (auto& v : x) v = rng.uniform(-1.0, 1.0);
  rl->reset();
  EXPECT_EQ(rl->observe().size(), static_cast<std::size_t>(rl->observation_dim()));
  for (int k = 0; !rl->done(); ++k) rl->step(std::vector<double>(x.begin() + 3 * k, x.begin() + 3 * k + 3));
  const auto ws = env.make_workspace();
  EXPECT_EQ(rl->final_loss(), env.loss(x, *ws, serial_team()));
  const double iou = env.episode_metric(*ws);
  EXPECT_GT(iou, 0.0);
  EXPECT_LT(iou, 1.0);
  EXPECT_EQ(env.info().metric, "soft_iou");
  // PlasticineLab's subsampling, x[::N // 200]: TripleMove's 9,999 particles give a stride of 49 and
  // 205 particles (0, 49, ..., 9996), then 6 spheres' poses
  const auto& triple = plb("plb-triplemove-h5");
  auto rl3 = triple.make_rl();
  EXPECT_EQ(rl3->observation_dim(), 205 * 6 + 6 * 7);
  rl3->reset();
  const auto o = rl3->observe();
  ASSERT_EQ(o.size(), 205u * 6 + 6 * 7);
  const auto& initial = triple.model().mpm.initial;
  for (int i : {0, 1, 204})
    for (int a = 0; a < 3; ++a) EXPECT_EQ(o[6 * i + a], initial[49 * i].x[a]) << "observed particle " << i;
}

TEST(Plb, BadNamesAreRefused) {
  EXPECT_THROW(make_env("plb-pinch-h7"), UsageError);
  EXPECT_THROW(make_env("plb-pinch-h"), UsageError);
  EXPECT_THROW(make_env("plb-nosuchtask"), UsageError);
  EXPECT_NO_THROW(make_env("plb-table-h10"));
}

// the task's row of `harness list`: name, results version, dim, differentiable, rl
std::string fmt_line(const Expected& e) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%-22s %7d %5d %14s %3s", (std::string("plb-") + e.task).c_str(),
                env_results_version("plb-" + std::string(e.task)), e.dim, "yes", "yes");
  return buf;
}

class PlbHarness : public dsb::testing::TempDirTest {};

TEST_F(PlbHarness, EveryTaskRunsEndToEndWithItsMetricStored) {
  auto r = testing::run_harness(dir_, "list");
  ASSERT_EQ(r.code, 0);
  for (const auto& e : kExpected) {
    const std::string line = fmt_line(e);
    EXPECT_NE(r.out.find(line), std::string::npos) << line;
  }
  std::string envs;
  for (const auto& t : mpm::plb_tasks()) envs += (envs.empty() ? "" : ",") + ("plb-" + t.name + "-h5");
  const std::string db = (dir_ / "plb.sqlite").string();
  r = testing::run_harness(dir_, "--env " + envs + " --optimizer cmaes --seeds 1 --budget 2 --quiet --db " + db);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto n = testing::episode_counts(db, "metric >= 0 AND metric <= 1");
  EXPECT_EQ(n.episodes, 16);
  EXPECT_EQ(n.finite, 16);
  EXPECT_EQ(n.matching, 16) << "every episode's soft IoU is stored";
}

}  // namespace
}  // namespace dsb
