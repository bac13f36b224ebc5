// The claims grid (`harness --claims`, harness/plan/claims_grid.hpp): the claims file compiled in is
// the repository's; it gives each env the optimizers its claims compare (every --all optimizer
// for an "is best" claim) and nothing for a claim the database cannot test; plan and slurm take
// it, and bad combinations exit 2 naming the value.
#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "harness/plan/claims_grid.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

const ClaimsEnv* find(const std::vector<ClaimsEnv>& envs, const std::string& name) {
  for (const auto& e : envs)
    if (e.env == name) return &e;
  return nullptr;
}

TEST(ClaimsGrid, TheCompiledClaimsAreTheRepositorysFile) {
  EXPECT_EQ(std::string(paper_claims_csv()),
            testing::read_file(std::string(DSB_SOURCE_DIR) + "/reports/paper_claims.csv"));
}

TEST(ClaimsGrid, EachEnvGetsTheOptimizersItsClaimsCompare) {
  const auto envs = claims_envs(paper_claims_csv());
  // an "is best" claim needs every rival
  ASSERT_NE(find(envs, "fluid"), nullptr);
  EXPECT_TRUE(find(envs, "fluid")->every_optimizer);
  EXPECT_TRUE(find(envs, "cartpole1")->every_optimizer);
  EXPECT_TRUE(find(envs, "plb-rope")->every_optimizer);
  // a_below_b: a then b; two claims on one env: their union, in the file's order
  const ClaimsEnv* c3 = find(envs, "cartpole3");
  ASSERT_NE(c3, nullptr);
  EXPECT_FALSE(c3->every_optimizer);
  EXPECT_EQ(c3->optimizers,
            (std::vector<std::string>{"gd", "rand-descents", "boleap", "nlopt-lbfgs", "cmaes", "random"}));
  const ClaimsEnv* pinch = find(envs, "plb-pinch");
  ASSERT_NE(pinch, nullptr);
  EXPECT_EQ(pinch->optimizers, (std::vector<std::string>{"boleap", "gd", "rand-descents", "nlopt-lbfgs", "cmaes"}));
  // 11 envs; a not_testable claim adds nothing
  EXPECT_EQ(envs.size(), 11u);
}

TEST(ClaimsGrid, ParsesQuotesAndRefusesAMalformedFile) {
  const auto envs = claims_envs(
      "id,env,kind,a,b,statement\n"
      "x,e1 e2,a_below_b,o1,o2 o3,\"says \"\"so\"\", with a comma\"\n"
      "y,e3,not_testable,o1,,\"a\nnewline\"\n");
  ASSERT_EQ(envs.size(), 2u);
  EXPECT_EQ(envs[1].env, "e2");
  EXPECT_EQ(envs[1].optimizers, (std::vector<std::string>{"o1", "o2", "o3"}));
  EXPECT_THROW(claims_envs("id,env,kind,a\nx,e,a_best,o\n"), UsageError);       // no column b
  EXPECT_THROW(claims_envs("id,env,kind,a,b\nx,e,a_best,\"o,\n"), UsageError);  // unclosed quote
  EXPECT_THROW(claims_envs("id,env,kind,a,b\nx,e,a_best,o\n"), UsageError);     // a short row
}

class ClaimsCli : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args) { return testing::run_harness(dir_, args); }
};

TEST_F(ClaimsCli, PlanPrintsTheClaimsGridAndItsSlurmCommand) {
  const auto all = harness("plan --claims --seeds 5 --db " + path("none.sqlite"));
  ASSERT_EQ(all.code, 0) << all.err;
  // fluid, cartpole1, plb-rope: 12 optimizers each; cartpole3 6; the seven other PlasticineLab tasks 5
  EXPECT_NE(all.out.find("plan: 385 runs in the grid"), std::string::npos) << all.out;
  EXPECT_NE(all.out.find("harness slurm --claims --seeds 5 --budget 1000"), std::string::npos) << all.out;
  const auto fluid = harness("plan --claims --env fluid --seeds 5 --db " + path("none.sqlite"));
  ASSERT_EQ(fluid.code, 0) << fluid.err;
  EXPECT_NE(fluid.out.find("plan: 60 runs in the grid"), std::string::npos) << fluid.out;
  const auto c3 = harness("plan --claims --env cartpole3 --seeds 2 --budget 10 --db " + path("none.sqlite"));
  EXPECT_NE(c3.out.find("plan: 12 runs in the grid"), std::string::npos) << c3.out;
}

TEST_F(ClaimsCli, SlurmTasksRunTheClaimsGrid) {
  const auto s = harness("slurm --claims --env cartpole3 --seeds 2 --budget 10 --shards 2 --dir " + path("s"));
  ASSERT_EQ(s.code, 0) << s.err;
  const std::string array = testing::read_file(path("s/array.sbatch"));
  EXPECT_NE(array.find("--claims --env cartpole3 --seeds 2 --budget 10"), std::string::npos) << array;
}

TEST_F(ClaimsCli, RunsExactlyTheClaimsRunsOfAnEnv) {
  const auto r = harness("--claims --env cartpole3 --seeds 1 --budget 3 --quiet --db " + path("c.sqlite"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("6 runs in the grid: 0 already done, 6 done now, 0 failed"), std::string::npos) << r.err;
}

TEST_F(ClaimsCli, BadCombinationsExitTwoNamingTheValue) {
  const auto with_all = harness("plan --claims --all --db " + path("none.sqlite"));
  EXPECT_EQ(with_all.code, 2);
  EXPECT_NE(with_all.err.find("--claims and --all"), std::string::npos) << with_all.err;
  const auto with_opt = harness("plan --claims --optimizer cmaes --db " + path("none.sqlite"));
  EXPECT_EQ(with_opt.code, 2);
  EXPECT_NE(with_opt.err.find("--optimizer cmaes"), std::string::npos) << with_opt.err;
  const auto other_env = harness("plan --claims --env sphere-10 --db " + path("none.sqlite"));
  EXPECT_EQ(other_env.code, 2);
  EXPECT_NE(other_env.err.find("--env sphere-10: no claim"), std::string::npos) << other_env.err;
  const auto knob = harness("plan --claims --env cartpole3 --set bo.init_points=3 --db " + path("none.sqlite"));
  EXPECT_EQ(knob.code, 2);
  EXPECT_NE(knob.err.find("--set bo.init_points: optimizer bo runs on none of the claims grid's envs that --env keeps"),
            std::string::npos)
      << knob.err;
  const auto left_out =
      harness("plan --claims --env cartpole3 --set plb-pinch.target=t.npy --db " + path("none.sqlite"));
  EXPECT_EQ(left_out.code, 2);
  EXPECT_NE(left_out.err.find("--set plb-pinch.target: env plb-pinch is in the claims grid, but --env leaves it out"),
            std::string::npos)
      << left_out.err;
  const auto neither = harness("plan --claims --env cartpole3 --set sphere-10.x=1 --db " + path("none.sqlite"));
  EXPECT_EQ(neither.code, 2);
  EXPECT_NE(neither.err.find("--set sphere-10.x: sphere-10 is neither an env nor an optimizer of the claims grid"),
            std::string::npos)
      << neither.err;
  EXPECT_FALSE(std::filesystem::exists(path("none.sqlite")));
}

}  // namespace
}  // namespace dsb
