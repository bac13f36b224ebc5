// `fluid` (envs/mpm/fluid_*): the model is resolved, a hand-found scoop lifts the cube out, the
// gradient agrees with central differences over the whole box, the RL view observes the cube and
// the ladle, and the harness runs and stores it. The env contract (test_env_contract.cpp) checks
// the rest: both paths, threads, the RL replay, frames and the config.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/mpm/fluid_env.hpp"
#include "envs/mpm/fluid_model.hpp"
#include "envs/registry.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using mpm::Vec3;

// forward/back then up/down speed of each segment: down beside the cube, forward along the floor
// with the bowl's lip under the cube, then up (found by hand, see docs/envs.md "fluid")
const std::vector<double> kScoop = {0.5, -1.0, 0.6, -1.0, 0.5, 0.2, -0.3, 1.0, -0.3, 1.0};

const mpm::FluidEnv& fluid(const std::string& name) { return static_cast<const mpm::FluidEnv&>(*shared_env(name)); }

TEST(Fluid, ModelIsResolved) {
  const auto& env = fluid("fluid");
  const auto& c = env.fluid_config();
  const double dx = c.mpm.dx;
  EXPECT_GE(c.cube_size / dx, 4.0) << "cube cells";
  EXPECT_GE(2.0 * (c.bowl_radius - c.bowl_thickness / 2) / dx, 6.0) << "bowl cells (inner diameter)";
  EXPECT_GE(c.syrup_depth / dx, 6.0) << "syrup cells";
  // tank 0.4 x 0.4 m between the walls, floor at 3 dx
  EXPECT_NEAR((c.mpm.grid[0] - 2 * c.mpm.bound) * dx, 0.4, 1e-12);
  EXPECT_NEAR((c.mpm.grid[2] - 2 * c.mpm.bound) * dx, 0.4, 1e-12);
  const auto& m = env.model();
  EXPECT_EQ(m.bodies[0].name, "cube");
  EXPECT_EQ(m.bodies[0].end - m.bodies[0].begin, 512);
  EXPECT_GT(m.particles(), 9000);
  // the cube is denser than the syrup, so it rests on the floor
  EXPECT_GT(c.cube.density, c.syrup.density);
}

TEST(Fluid, HandFoundScoopLiftsTheCubeAboveTheRim) {
  const auto& env = fluid("fluid");
  const auto points = env.trajectory(kScoop, serial_team());
  const double floor = env.fluid_config().floor_y();
  const double start = points.front().cube.y() - floor, end = points.back().cube.y() - floor;
  EXPECT_LT(start, 0.05) << "the cube starts on the floor";
  EXPECT_GT(end, env.fluid_config().rim_height) << "and ends above the tank's rim";
  // without the ladle moving the cube stays on the floor
  const auto still = env.trajectory(std::vector<double>(10, 0.0), serial_team());
  EXPECT_LT(still.back().cube.y() - floor, 0.05);
  EXPECT_GT(env.loss(std::vector<double>(10, 0.0)), env.loss(kScoop));
  // the episode's second metric is that final height, the same from the forward and the gradient
  // rollout, bit for bit
  EXPECT_EQ(env.info().metric, "cube_height");
  const auto ws = env.make_workspace();
  env.loss(kScoop, *ws, serial_team());
  EXPECT_EQ(env.episode_metric(*ws), end);
  std::vector<double> grad(10);
  env.loss(std::vector<double>(10, 0.0), *ws, serial_team());
  EXPECT_EQ(env.episode_metric(*ws), still.back().cube.y() - floor);
  env.loss_and_grad(kScoop, grad, *ws, serial_team());
  EXPECT_EQ(env.episode_metric(*ws), end);
}

TEST(Fluid, GradientMatchesCentralDifferences) {
  // short horizon (5 env steps, 40 substeps) where differences are trustworthy; contact makes the
  // loss only piecewise smooth, so differences carry ~1e-9 of noise: an absolute floor of 1e-8
  const auto& env = fluid("fluid-h5");
  GradientCheckOptions options;
  options.step = 1e-6;
  options.tolerance = 1e-4;
  options.absolute_floor = 1e-8;
  Rng rng(5);
  for (int point = 0; point < 3; ++point) {
    std::vector<double> x(10);
    for (auto& v : x) v = rng.uniform(-1.0, 1.0);
    const auto r = check_gradient(env, x, options);
    EXPECT_TRUE(r.value_agrees);
    EXPECT_GT(r.max_abs_central, 1e-3) << "degenerate point";
    EXPECT_TRUE(r.passed) << "point " << point << ": worst coordinate " << r.worst_coordinate << " relative error "
                          << r.worst_relative_error;
  }
}

TEST(Fluid, RlViewReplaysTheEpisode) {
  const auto& env = fluid("fluid-h10");
  auto rl = env.make_rl();
  ASSERT_TRUE(rl);
  EXPECT_EQ(rl->action_dim(), 2);
  // the paper's "object and ladle positions": the cube's centre, then the bowl's
  EXPECT_EQ(rl->observation_dim(), 6);
  EXPECT_EQ(rl->horizon(), 10);
  rl->reset();
  const auto obs0 = rl->observe();
  ASSERT_EQ(obs0.size(), 6u);
  const double floor = env.fluid_config().floor_y();
  EXPECT_LT(obs0[1] - floor, 0.05);  // cube on the floor
  const auto& start = env.fluid_config().ladle_start;
  for (int a = 0; a < 3; ++a) EXPECT_EQ(obs0[3 + a], start[a]) << a;
  // the ladle is kinematic: one env step at full forward speed moves the bowl by max_speed x dt x substeps
  rl->step(std::vector<double>{1.0, 0.0});
  const auto& cfg = env.fluid_config();
  EXPECT_NEAR(rl->observe()[3], start[0] + cfg.max_speed * cfg.mpm.dt * cfg.mpm.substeps, 1e-12);
  EXPECT_NEAR(rl->observe()[4], start[1], 1e-12);
  // the replay of a param vector's actions: the env contract (test_env_contract.cpp)
}

TEST(Fluid, BadNamesAreRefused) {
  EXPECT_THROW(make_env("fluid-h7"), UsageError);
  EXPECT_THROW(make_env("fluid-h55"), UsageError);
  EXPECT_THROW(make_env("fluid-hx"), UsageError);
  EXPECT_NO_THROW(make_env("fluid-h25"));
}

class FluidHarness : public dsb::testing::TempDirTest {};

TEST_F(FluidHarness, ListEvalAndAGridOfCmaesAndGd) {
  auto r = testing::run_harness(dir_, "list");
  ASSERT_EQ(r.code, 0);
  // its row of `harness list`: name, results version, dim, differentiable, rl
  char row[96];
  std::snprintf(row, sizeof row, "%-22s %7d %5d %14s %3s", "fluid", env_results_version("fluid"), 10, "yes", "yes");
  EXPECT_NE(r.out.find(row), std::string::npos) << r.out;

  r = testing::run_harness(dir_, "eval --env fluid --x 0.5,-1,0.6,-1,0.5,0.2,-0.3,1,-0.3,1 --grad");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(std::isfinite(j["loss"].get<double>()));
  ASSERT_EQ(j["grad"].size(), 10u);
  for (const auto& g : j["grad"]) EXPECT_TRUE(std::isfinite(g.get<double>()));

  const std::string db = (dir_ / "fluid.sqlite").string();
  r = testing::run_harness(dir_, "--env fluid --optimizer cmaes,gd --seeds 1 --budget 3 --quiet --db " + db);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto n = testing::episode_counts(db);
  EXPECT_EQ(n.episodes, 6);
  EXPECT_EQ(n.finite, 6) << "every episode finite";
  EXPECT_EQ(n.matching, 3) << "gd's episodes carry gradients";
  // every episode stores the cube's final height (metres above the floor, inside the domain)
  EXPECT_EQ(testing::episode_counts(db, "metric > 0 AND metric < 0.4").matching, 6);
}

}  // namespace
}  // namespace dsb
