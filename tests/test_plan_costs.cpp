// The grid's cost model and its uses: the progress line's share of the estimated work and ETA,
// cheapest-first order, shards cut from run keys, durations as the plan prints them.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "harness/cost_model.hpp"
#include "harness/plan.hpp"
#include "harness/plan_report.hpp"
#include "harness/progress.hpp"

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
