// The env core: metadata without models (listing and grid expansion build none), one shared
// lazily built model per env, and the 10,000-D threaded rollouts giving the same bits for 1, 2 and
// 3 threads. What every env promises (reused workspaces, both paths, 1 and 2 threads, the RL view,
// frames, its config's text) is checked env by env in test_env_contract.cpp.
#include <vector>

#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/core/lazy_model.hpp"
#include "envs/registry.hpp"
#include "harness/plan/grid.hpp"

namespace dsb {
namespace {

TEST(EnvCore, MetadataAndGridExpansionBuildNoModel) {
  const std::int64_t before = lazy_model_builds();
  GridRequest all;
  all.all = true;
  all.seeds = 5;
  const auto grid = expand_grid(all);
  EXPECT_GT(grid.size(), 500u);
  for (const auto& name : grid_env_names()) {
    const auto env = shared_env(name);
    EXPECT_EQ(env->info().name, name);
    EXPECT_GT(env->dim(), 0);
    (void)env->config();
  }
  EXPECT_EQ(lazy_model_builds(), before) << "metadata or config built a model";
  EXPECT_TRUE(shared_env("cartpole3")->supports_rl());
  EXPECT_FALSE(shared_env("bounce")->supports_rl());
}

TEST(EnvCore, SharedEnvBuildsItsModelOnceOnFirstRollout) {
  const auto a = shared_env("pinball-1x2");
  EXPECT_EQ(a.get(), shared_env("pinball-1x2").get());
  const std::int64_t before = lazy_model_builds();
  const std::vector<double> x{0.1, -0.2};
  const double l1 = a->loss(x);
  const std::int64_t after_first = lazy_model_builds();
  EXPECT_LE(after_first - before, 1);  // 0 when another test already built it
  EXPECT_EQ(a->loss(x), l1);
  EXPECT_EQ(lazy_model_builds(), after_first);
}

TEST(EnvCore, ThreadedRolloutsAreBitIdenticalForAnyThreadCount) {
  for (const std::string name :
       {"sphere-10000", "rosenbrock-10000", "rastrigin-10000", "ackley-10000", "styblinski-10000"}) {
    const auto env = make_env(name);
    ASSERT_TRUE(env->info().threaded) << name;
    Rng rng(8);
    std::vector<double> x(env->dim());
    for (double& v : x) v = rng.uniform(-1.0, 1.0);
    const auto ws = env->make_workspace();
    std::vector<double> g1(env->dim());
    const double l1 = env->loss_and_grad(x, g1, *ws, serial_team());
    for (const int threads : {2, 3}) {
      ThreadTeam team(threads);
      std::vector<double> g(env->dim());
      EXPECT_EQ(env->loss_and_grad(x, g, *ws, team), l1) << name << ", " << threads << " threads";
      EXPECT_EQ(g, g1) << name << ", " << threads << " threads";
      EXPECT_EQ(env->loss(x, *ws, team), l1) << name;
    }
  }
}

}  // namespace
}  // namespace dsb
