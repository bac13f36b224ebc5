// The grid's cost model and its uses: the progress line's share of the estimated work and ETA,
// cheapest-first order, shards cut from run keys, durations as the plan prints them; a plan that
// takes a database's measured walls, Slurm time limits from the plan, and no optimizer's name in
// the harness (its costs come from the registry).
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "harness/cost_model.hpp"
#include "harness/plan.hpp"
#include "harness/plan_report.hpp"
#include "harness/progress.hpp"
#include "harness/slurm_command.hpp"
#include "optimizers/core/registry.hpp"
#include "support/harness_process.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

TEST(Progress, TheEstimatedWorkDoneCountsFinishedRunsAndTheEpisodesOfRunningOnes) {
  // two runs of 10 episodes, estimated 100 s and 300 s
  Progress p(2, 20, 400.0, 2, nullptr);
  p.start();
  // before 2% of the work is done (and within the first second) the ETA is the plan's: 400 s / 2 workers
  EXPECT_NE(p.line().find("0.0% of the estimated work, ETA 00:03:20 (planned)"), std::string::npos) << p.line();
  p.run_started(0, 10.0);  // 100 s / 10 episodes
  p.run_started(1, 30.0);
  p.episodes_of(0) += 4;   // 40 s of work
  p.episodes_of(1) += 2;   // 60 s
  EXPECT_NE(p.line().find("episodes 6/20"), std::string::npos) << p.line();
  EXPECT_NE(p.line().find("25.0% of the estimated work, ETA 00:02:30 (planned)"), std::string::npos) << p.line();
  p.episodes_of(0) += 6;
  p.run_finished(0, false, 100.0);  // the finished run counts at its estimate, not twice
  EXPECT_NE(p.line().find("runs 1/2 (0 failed)"), std::string::npos) << p.line();
  EXPECT_NE(p.line().find("40.0% of the estimated work"), std::string::npos) << p.line();
}

TEST(Progress, TheEtaExtrapolatesTheSpeedSeenOnceTwoPercentOfTheWorkIsDone) {
  Progress p(2, 20, 100.0, 1, nullptr);
  p.start();
  p.run_started(0, 5.0);
  p.episodes_of(0) += 10;
  p.run_finished(0, false, 50.0);  // half the work
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  // half done in the elapsed time: as much again is left, from the speed seen, not the plan's 50 s
  // (read back from the line itself, so a slow machine cannot fail it)
  const std::string line = p.line();
  EXPECT_EQ(line.find("planned"), std::string::npos) << line;
  const auto at_elapsed = line.find("elapsed "), at_eta = line.find("ETA 00:");
  ASSERT_NE(at_elapsed, std::string::npos) << line;
  ASSERT_NE(at_eta, std::string::npos) << line;
  const double elapsed = std::stod(line.substr(at_elapsed + 8));
  const int eta = std::stoi(line.substr(at_eta + 7, 2)) * 60 + std::stoi(line.substr(at_eta + 10, 2));
  EXPECT_NE(line.find("50.0% of the estimated work"), std::string::npos) << line;
  EXPECT_LE(std::abs(eta - elapsed), 1.0) << line;
}

TEST(PlanOrder, CheapestFirstIsStableSoEqualCostsKeepGridOrder) {
  const std::vector<double> cost = {5.0, 1.0, 5.0, 0.5, 1.0};
  const std::vector<std::size_t> want = {3, 1, 4, 0, 2};
  EXPECT_EQ(cheapest_first(cost), want);
}

TEST(Shards, AShardIsAFunctionOfTheRunKeyAlone) {
  const RunKey a{"fluid", "cmaes", 3, 1000, "e", "o", "0.1.0"};
  RunKey other_version = a;
  other_version.harness_version = "9.9.9";
  RunKey other_seed = a;
  other_seed.seed = 4;
  EXPECT_EQ(shard_of(a, 7), shard_of(a, 7));
  EXPECT_EQ(shard_of(a, 7), shard_of(other_version, 7));  // a new version keeps the cut
  EXPECT_EQ(shard_of(a, 1), 0);
  // spread: 1,000 seeds over 10 shards, each shard between 70 and 130 runs
  std::vector<int> count(10, 0);
  for (int s = 0; s < 1000; ++s) {
    other_seed.seed = s;
    ++count[static_cast<std::size_t>(shard_of(other_seed, 10))];
  }
  for (int c : count) {
    EXPECT_GT(c, 70);
    EXPECT_LT(c, 130);
  }
}

TEST(Plan, DurationsReadAsTheyShould) {
  EXPECT_EQ(human_duration(0.0042), "0.0042 s");
  EXPECT_EQ(human_duration(42.0), "42 s");
  EXPECT_EQ(human_duration(600.0), "10 min");
  EXPECT_EQ(human_duration(3.0 * 3600.0), "3.0 h");
  EXPECT_EQ(human_duration(3.0 * 86400.0), "3.0 days");
}

}  // namespace
}  // namespace dsb

namespace dsb {
namespace {

class PlanFromDatabase : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args) { return testing::run_harness(dir_, args); }
};

TEST_F(PlanFromDatabase, DoneRunsOfAGroupCostItsPendingRunsByTheirMedianWall) {
  ASSERT_EQ(harness("--env cartpole1 --optimizer cmaes,random --seeds 2 --budget 30 --quiet --db " + path("m.sqlite")).code, 0);
  const auto p = harness("plan --env cartpole1 --optimizer cmaes,gd --seeds 4 --budget 30 --db " + path("m.sqlite") +
                         " --runs-csv " + path("runs.csv"));
  ASSERT_EQ(p.code, 0) << p.err;
  EXPECT_NE(p.out.find("2 runs costed from the median wall time of their group's done runs"), std::string::npos)
      << p.out;
  const std::string csv = testing::read_file(path("runs.csv"));
  EXPECT_EQ(csv.rfind("env,optimizer,seed,budget,planned_s,source\n", 0), 0u) << csv;
  // cmaes seeds 2 and 3 at the median of seeds 0 and 1 (their mean), gd from the model
  const double median = std::stod(testing::scalar(
      path("m.sqlite"), "SELECT printf('%.17g', avg(wall_s)) FROM runs WHERE optimizer='cmaes'"));
  const auto at = csv.find("cartpole1,cmaes,2,30,");
  ASSERT_NE(at, std::string::npos) << csv;
  EXPECT_NEAR(std::stod(csv.substr(at + 21)), median, 1e-5 * median) << csv;
  EXPECT_NE(csv.find("cartpole1,cmaes,3,30,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",measured\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("cartpole1,gd,0,30,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",model\n"), std::string::npos) << csv;
}

TEST_F(PlanFromDatabase, SlurmTakesItsTimeLimitFromThePlanUnlessGivenOne) {
  const auto s = harness("slurm --env cartpole1 --optimizer cmaes --seeds 2 --budget 30 --shards 2 --dir " + path("c"));
  ASSERT_EQ(s.code, 0) << s.err;
  const std::string array = testing::read_file(path("c/array.sbatch"));
  EXPECT_NE(array.find("#SBATCH --time=0-00:15:"), std::string::npos) << array;  // a short grid: the 15 min extra
  EXPECT_NE(s.out.find("the plan's longest task"), std::string::npos) << s.out;
  const auto t = harness("slurm --env cartpole1 --optimizer cmaes --seeds 2 --budget 30 --shards 2 --time 2:00:00 --dir " +
                         path("d"));
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_NE(testing::read_file(path("d/array.sbatch")).find("#SBATCH --time=2:00:00"), std::string::npos);
  EXPECT_EQ(slurm_time_limit(3600.0), "0-01:45:00");  // 1.5 h + 15 min
}

TEST(PlanCosts, NoOptimizerIsNamedInTheHarness) {
  // their costs, families and seed use come from the registry: harness/ code names none of them
  for (const auto& entry : std::filesystem::directory_iterator(std::string(DSB_SOURCE_DIR) + "/harness")) {
    // the code without its comments (a comment may give an example)
    std::string text;
    std::istringstream lines(testing::read_file(entry.path()));
    for (std::string line; std::getline(lines, line);) text += line.substr(0, line.find("//")) + "\n";
    for (const auto& opt : optimizer_entries())
      EXPECT_EQ(text.find("\"" + opt.name + "\""), std::string::npos)
          << entry.path().filename() << " names optimizer '" << opt.name << "'";
  }
}

}  // namespace
}  // namespace dsb
