// The grid's cost model and its uses: the progress line's share of the estimated work and ETA,
// the run order (cheapest first, sharing leads pulled ahead), shards cut from run keys, durations as the plan prints them; a plan that
// takes a database's measured walls, Slurm time limits from the plan, and no optimizer's name in
// the harness (its costs come from the registry).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "harness/plan/cost_model.hpp"
#include "harness/plan/grid.hpp"
#include "harness/plan/plan.hpp"
#include "harness/plan/plan_report.hpp"
#include "harness/run/probe.hpp"
#include "harness/run/progress.hpp"
#include "harness/plan/run_order.hpp"
#include "harness/commands/slurm_command.hpp"
#include "optimizers/bo/gp_cost.hpp"
#include "optimizers/registry.hpp"
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
  p.episodes_of(0) += 4;  // 40 s of work
  p.episodes_of(1) += 2;  // 60 s
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

// a planned run of a made-up env with a registered optimizer (its registration resolved, as the
// grid's expansion resolves it)
PlannedRun planned(const std::string& env, const std::string& opt, int seed, std::int64_t budget = 100) {
  PlannedRun run{RunSpec{env, opt, seed, budget}, RunKey{env, opt, seed, budget, "e", "o", "0.1.0"}};
  run.spec.entry = &optimizer_entry(opt);
  return run;
}

std::vector<PlannedRun> runs_of(const std::vector<std::tuple<std::string, std::string, int>>& specs) {
  std::vector<PlannedRun> runs;
  for (const auto& [env, opt, seed] : specs) runs.push_back(planned(env, opt, seed));
  return runs;
}

TEST(PlanOrder, WithoutSharingTheOrderIsCheapestFirst) {
  const auto runs = runs_of({{"a", "gd", 0}, {"a", "gd", 1}, {"b", "cmaes", 0}});
  const std::vector<double> cost = {5.0, 3.0, 1.0};
  EXPECT_EQ(run_order(runs, cost, false, 2), cheapest_first(cost));
  // cmaes draws at its start: no group has a lead, so sharing leaves cheapest first too
  const auto drawing = runs_of({{"a", "cmaes", 0}, {"a", "cmaes", 1}, {"b", "cmaes", 0}});
  EXPECT_EQ(run_order(drawing, cost, true, 2), cheapest_first(cost));
}

TEST(PlanOrder, LightRunsReportFirstAndAnExpensiveLeadEndsAsItsFollowersAreDue) {
  // an expensive gd group of 5 seeds (the lead 300 s, each follower 30 s: 90% of it replayed),
  // 20 tiny runs of 1 s and 100 light ones of 10 s (cmaes: no sharing), on 2 workers
  std::vector<std::tuple<std::string, std::string, int>> specs;
  std::vector<double> cost;
  for (int s = 0; s < 5; ++s) specs.emplace_back("heavy", "gd", s), cost.push_back(s == 0 ? 300.0 : 30.0);
  for (int s = 0; s < 20; ++s) specs.emplace_back("tiny", "cmaes", s), cost.push_back(1.0);
  for (int s = 0; s < 100; ++s) specs.emplace_back("light", "cmaes", s), cost.push_back(10.0);
  const auto runs = runs_of(specs);
  const auto lead = share_leads(runs);
  ASSERT_EQ(lead[1], 0);
  const auto order = run_order(runs, cost, true, 2);
  std::vector<std::size_t> at(order.size());
  for (std::size_t r = 0; r < order.size(); ++r) at[order[r]] = r;
  // the lead comes before its followers, and the tiny runs before the lead
  for (std::size_t f = 1; f < 5; ++f) EXPECT_LT(at[0], at[f]);
  for (std::size_t t = 5; t < 25; ++t) EXPECT_LT(at[t], at[0]);
  const auto end_of = [](const std::vector<double>& e, std::size_t from, std::size_t to) {
    return *std::max_element(e.begin() + static_cast<std::ptrdiff_t>(from),
                             e.begin() + static_cast<std::ptrdiff_t>(to));
  };
  const auto end = runner_end_times(order, cost, lead, 2);
  // the tiny env is done after its 20 s of work on 2 workers; no worker ever waits:
  // (300 + 4 x 30 + 20 + 1000) s of work over 2 workers = 720 s
  EXPECT_DOUBLE_EQ(end_of(end, 5, 25), 10.0);
  EXPECT_DOUBLE_EQ(end_of(end, 0, end.size()), 720.0);
  // leads first (the earlier order) holds a worker from the start: the tiny env ends at 20 s
  std::vector<std::size_t> leads_first = {0};
  for (const std::size_t i : cheapest_first(cost))
    if (i != 0) leads_first.push_back(i);
  const auto end_lf = runner_end_times(leads_first, cost, lead, 2);
  EXPECT_DOUBLE_EQ(end_of(end_lf, 5, 25), 20.0);
  // cheapest first reaches the lead last, and a worker waits while it runs alone
  const auto end_cf = runner_end_times(cheapest_first(cost), cost, lead, 2);
  EXPECT_DOUBLE_EQ(end_of(end_cf, 0, end_cf.size()), 870.0);
}

TEST(PlanOrder, FollowersWaitForTheirLeadSoAGroupOnManyCoresTakesLeadPlusFollower) {
  // a 5-seed gd group (lead 100 s, each follower 80 s) on 4 workers: the followers start together
  // when the lead ends, 180 s, where the work over the workers is 105 s
  std::vector<std::tuple<std::string, std::string, int>> specs;
  std::vector<double> cost;
  for (int s = 0; s < 5; ++s) specs.emplace_back("heavy", "gd", s), cost.push_back(s == 0 ? 100.0 : 80.0);
  const auto runs = runs_of(specs);
  EXPECT_DOUBLE_EQ(runner_wall(runs, cost, true, 4), 180.0);
  // without sharing nobody waits, and the order is cheapest first: the four followers, then the
  // lead, 80 + 100 s; four 20 s runs and a 100 s one, 20 + 100 s
  EXPECT_DOUBLE_EQ(runner_wall(runs, cost, false, 4), 180.0);
  EXPECT_DOUBLE_EQ(runner_wall(runs, {100.0, 20.0, 20.0, 20.0, 20.0}, false, 4), 120.0);
  // with 3 light runs of 30 s beside it the free workers take them while the lead runs
  for (int s = 0; s < 3; ++s) specs.emplace_back("light", "cmaes", s), cost.push_back(30.0);
  EXPECT_DOUBLE_EQ(runner_wall(runs_of(specs), cost, true, 4), 180.0);
  // one worker: the sum, whatever waits
  EXPECT_DOUBLE_EQ(runner_wall(runs_of(specs), cost, true, 1), 100.0 + 4 * 80.0 + 3 * 30.0);
  // a follower whose lead is not in the order never starts (and the rest still run)
  const auto end = runner_end_times({1, 2}, {100.0, 80.0, 30.0}, {-1, 0, -1}, 2);
  EXPECT_EQ(end, (std::vector<double>{-1.0, -1.0, 30.0}));
}

TEST(PlanOrder, AResumedGroupWhoseDonorIsStoredWaitsForNoLead) {
  // seeds 1-4 of a gd group whose seed 0 is done (80 s each, on 2 workers): without the stored
  // donor seed 1 would lead and the rest wait for it, 80 + 2 x 80 s; with it they pair up, 2 x 80 s
  std::vector<std::tuple<std::string, std::string, int>> specs;
  for (int s = 1; s < 5; ++s) specs.emplace_back("heavy", "gd", s);
  GridPlan plan;
  plan.pending = runs_of(specs);
  const std::vector<double> cost(4, 80.0);
  EXPECT_EQ(share_leads(plan.pending), (std::vector<std::ptrdiff_t>{-1, 0, 0, 0}));
  EXPECT_DOUBLE_EQ(runner_wall(plan.pending, cost, true, 2), 240.0);
  estimate_sharing(plan, {{plan.pending[0].key.group(), 60}});
  for (const PlannedRun& p : plan.pending) EXPECT_TRUE(p.donor_stored) << p.key.text();
  EXPECT_EQ(share_leads(plan.pending), (std::vector<std::ptrdiff_t>(4, -1)));
  EXPECT_DOUBLE_EQ(runner_wall(plan.pending, cost, true, 2), 160.0);
  EXPECT_EQ(plan.shared_share, (std::vector<double>(4, 0.6)));  // 60 of the budget's 100 episodes
  // another group's stored donor changes nothing; an optimizer that draws at its start never shares
  GridPlan other;
  other.pending = runs_of({{"heavy", "gd", 1}, {"heavy", "gd", 2}, {"heavy", "cmaes", 1}});
  estimate_sharing(other, {{planned("light", "gd", 0).key.group(), 60}});
  EXPECT_EQ(share_leads(other.pending), (std::vector<std::ptrdiff_t>{-1, 0, -1}));
  for (const PlannedRun& p : other.pending) EXPECT_FALSE(p.donor_stored) << p.key.text();
}

TEST(Shards, AShardIsAFunctionOfTheRunKeyAlone) {
  const PlannedRun a = planned("fluid", "cmaes", 3, 1000);
  PlannedRun other_version = a;
  other_version.key.harness_version = "9.9.9";
  PlannedRun other_seed = a;
  EXPECT_EQ(shard_of(a, 7), shard_of(a, 7));
  EXPECT_EQ(shard_of(a, 7), shard_of(other_version, 7));  // a new version keeps the cut
  EXPECT_EQ(shard_of(a, 1), 0);
  // spread: 1,000 seeds over 10 shards, each shard between 70 and 130 runs
  std::vector<int> count(10, 0);
  for (int s = 0; s < 1000; ++s) {
    other_seed.key.seed = s;
    ++count[static_cast<std::size_t>(shard_of(other_seed, 10))];
  }
  for (int c : count) {
    EXPECT_GT(c, 70);
    EXPECT_LT(c, 130);
  }
}

TEST(Shards, ASharingGroupIsOneSliceUnlessNothingIsShared) {
  // gd never draws: its seeds share, so they fall in one shard; with --no-sharing (group_seeds
  // false) each run hashes its own seed and 1,000 seeds spread over 10 shards like cmaes's
  PlannedRun gd = planned("fluid", "gd", 0, 1000);
  const int group_shard = shard_of(gd, 10);
  std::vector<int> grouped(10, 0), alone(10, 0);
  for (int s = 0; s < 1000; ++s) {
    gd.key.seed = s;
    ++grouped[static_cast<std::size_t>(shard_of(gd, 10))];
    ++alone[static_cast<std::size_t>(shard_of(gd, 10, false))];
  }
  EXPECT_EQ(grouped[static_cast<std::size_t>(group_shard)], 1000);
  for (int c : alone) {
    EXPECT_GT(c, 70);
    EXPECT_LT(c, 130);
  }
  // an optimizer that draws at its start never groups: group_seeds changes nothing for it
  PlannedRun cmaes = planned("fluid", "cmaes", 0, 1000);
  for (int s = 0; s < 50; ++s) {
    cmaes.key.seed = s;
    EXPECT_EQ(shard_of(cmaes, 10), shard_of(cmaes, 10, false));
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
  ASSERT_EQ(
      harness("--env cartpole1 --optimizer cmaes,random --seeds 2 --budget 30 --quiet --db " + path("m.sqlite")).code,
      0);
  const auto p = harness("plan --env cartpole1 --optimizer cmaes,gd --seeds 4 --budget 30 --db " + path("m.sqlite") +
                         " --runs-csv " + path("runs.csv"));
  ASSERT_EQ(p.code, 0) << p.err;
  EXPECT_NE(p.out.find("2 runs costed from the median wall time of their group's done runs"), std::string::npos)
      << p.out;
  const std::string csv = testing::read_file(path("runs.csv"));
  EXPECT_EQ(csv.rfind("env,optimizer,seed,budget,planned_s,source,start_rank,lead_seed\n", 0), 0u) << csv;
  // cmaes seeds 2 and 3 at the median of seeds 0 and 1 (their mean), gd from the model
  const double median = std::stod(
      testing::scalar(path("m.sqlite"), "SELECT printf('%.17g', avg(wall_s)) FROM runs WHERE optimizer='cmaes'"));
  const auto at = csv.find("cartpole1,cmaes,2,30,");
  ASSERT_NE(at, std::string::npos) << csv;
  EXPECT_NEAR(std::stod(csv.substr(at + 21)), median, 1e-5 * median) << csv;
  EXPECT_NE(csv.find("cartpole1,cmaes,3,30,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",measured,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("cartpole1,gd,0,30,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",model,"), std::string::npos) << csv;
  // gd's seeds 1-3 wait for seed 0 and replay it; cmaes draws at its start and waits for none
  EXPECT_NE(csv.find("cartpole1,gd,3,30,"), std::string::npos) << csv;
  EXPECT_EQ(csv.substr(csv.find('\n', csv.find("cartpole1,gd,3,30,")) - 2, 2), ",0") << csv;
  EXPECT_EQ(csv.substr(csv.find('\n', csv.find("cartpole1,cmaes,3,30,")) - 1, 1), ",") << csv;
}

TEST_F(PlanFromDatabase, SeedsOfAGroupWhoseLeadIsDoneWaitForNoneOfThem) {
  // gd's seed 0 done: seeds 1-3 replay its stored episodes, each at once, none waiting for seed 1
  ASSERT_EQ(harness("--env cartpole1 --optimizer gd --seeds 1 --budget 30 --quiet --db " + path("g.sqlite")).code, 0);
  ASSERT_GT(std::stoi(testing::scalar(path("g.sqlite"), "SELECT seed_free_episodes FROM runs")), 0);
  const auto p = harness("plan --env cartpole1 --optimizer gd --seeds 4 --budget 30 --db " + path("g.sqlite") +
                         " --runs-csv " + path("runs.csv"));
  ASSERT_EQ(p.code, 0) << p.err;
  const std::string csv = testing::read_file(path("runs.csv"));
  for (const std::string seed : {"1", "2", "3"}) {
    const auto at = csv.find("cartpole1,gd," + seed + ",30,");
    ASSERT_NE(at, std::string::npos) << csv;
    EXPECT_EQ(csv.substr(csv.find('\n', at) - 1, 1), ",") << seed << ": " << csv;
  }
}

TEST_F(PlanFromDatabase, SlurmTakesItsTimeLimitFromThePlanUnlessGivenOne) {
  const auto s = harness("slurm --env cartpole1 --optimizer cmaes --seeds 2 --budget 30 --shards 2 --dir " + path("c"));
  ASSERT_EQ(s.code, 0) << s.err;
  const std::string array = testing::read_file(path("c/array.sbatch"));
  EXPECT_NE(array.find("#SBATCH --time=0-00:15:"), std::string::npos) << array;  // a short grid: the 15 min extra
  EXPECT_NE(s.out.find("the plan's longest task"), std::string::npos) << s.out;
  const auto t = harness(
      "slurm --env cartpole1 --optimizer cmaes --seeds 2 --budget 30 --shards 2 --time 2:00:00 --dir " + path("d"));
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_NE(testing::read_file(path("d/array.sbatch")).find("#SBATCH --time=2:00:00"), std::string::npos);
  EXPECT_EQ(slurm_time_limit(3600.0), "0-01:45:00");  // 1.5 h + 15 min
}

TEST_F(PlanFromDatabase, ThePlansSlurmLineNamesTheLargestTaskWhichSlurmTakesItsLimitFrom) {
  // the claims grid at the cost hints: runs are cut by run-key hash, so tasks differ, and the plan
  // names the largest, the one `harness slurm` sets its time limit from (one core per task)
  const auto p = harness("plan --claims --seeds 5");
  ASSERT_EQ(p.code, 0) << p.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(p.out, m, std::regex(R"(--shards (\d+) .* of (\S+ \S+) \(median\) up to (\S+ \S+):)")))
      << p.out;
  const std::string shards = m[1], median = m[2], largest = m[3];
  EXPECT_NE(median, largest) << p.out;
  const auto s = harness("slurm --claims --seeds 5 --shards " + shards + " --dir " + path("e"));
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.out.find("the plan's longest task, " + largest + ","), std::string::npos) << p.out << s.out;
}

// the planned seconds of (env, optimizer, seed) in a --runs-csv file
double planned_seconds(const std::string& csv, const std::string& prefix) {
  const auto at = csv.find(prefix);
  if (at == std::string::npos) return -1.0;
  return std::stod(csv.substr(at + prefix.size()));
}

TEST_F(PlanFromDatabase, SlurmsTimeLimitLetsASharingGroupsFollowersWaitForTheirLead) {
  // nlopt-lbfgs on plb-pinch: its 5 seeds are one sharing group in one task, the followers replay
  // the lead's first episodes and start when it ends; on 4 CPUs the task takes lead + follower,
  // not the group's work over the CPUs (harness slurm until 2026-12-06)
  const std::string grid = "--env plb-pinch --optimizer nlopt-lbfgs --seeds 5 --budget 1000";
  const auto p = harness("plan " + grid + " --db " + path("p.sqlite") + " --runs-csv " + path("runs.csv"));
  ASSERT_EQ(p.code, 0) << p.err;
  const std::string csv = testing::read_file(path("runs.csv"));
  const double lead = planned_seconds(csv, "plb-pinch,nlopt-lbfgs,0,1000,");
  const double follower = planned_seconds(csv, "plb-pinch,nlopt-lbfgs,1,1000,");
  ASSERT_GT(lead, 0.0) << csv;
  ASSERT_GT(follower, 0.0) << csv;
  ASSERT_LT(follower, lead) << csv;  // it replays part of the lead
  const std::string waits = human_duration(lead + follower);
  const std::string spread = human_duration(std::max(lead, (lead + 4 * follower) / 4));
  ASSERT_NE(waits, spread);
  const auto s = harness("slurm " + grid + " --shards 1 --cpus-per-task 4 --dir " + path("s"));
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.out.find("the plan's longest task, " + waits + ","), std::string::npos) << s.out;
  // and the plan of the same grid with --jobs 4 says that wall too
  const auto j = harness("plan " + grid + " --jobs 4 --db " + path("p.sqlite"));
  ASSERT_EQ(j.code, 0) << j.err;
  EXPECT_NE(j.out.find("with --jobs 4 --threads 1: about " + waits + " wall"), std::string::npos) << j.out;
}

TEST_F(PlanFromDatabase, CalibrateTimesCheapPairsAndThePlanCountsTheirMeasuredSeconds) {
  const std::string cache = "DSB_COST_CACHE=" + path("costs.json");
  // cartpole3 is cheap: cmaes and gd run their whole budget, boleap (a modelled GP time) 200
  // episodes, ppo the 41 episodes of 100 decisions that hold two of its 2,048-decision rollouts
  const std::string grid = "--env cartpole3 --optimizer cmaes,boleap,ppo,gd --seeds 2 --budget 300";
  const auto c = testing::run_harness(dir_, "calibrate " + grid, cache);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto j = nlohmann::json::parse(testing::read_file(path("costs.json")));
  ASSERT_EQ(j.at("runs").size(), 4u) << j.dump();
  double cmaes_s = 0.0, boleap_s = 0.0, ppo_s = 0.0, gd_s = 0.0, gd_replay_s = 0.0;
  for (const auto& [key, v] : j.at("runs").items()) {
    EXPECT_GT(v.at("seconds").get<double>(), 0.0) << key;
    ASSERT_EQ(key.rfind("cartpole3|", 0), 0u) << key;
    if (key.find("|gd|") != std::string::npos) {
      EXPECT_EQ(v.at("episodes").get<int>(), 300) << key;
      gd_s = v.at("seconds").get<double>();
      // gd never draws: its probe is replayed from its journal, as a later seed replays it
      gd_replay_s = v.at("replay_s_per_episode").get<double>();
      EXPECT_GT(gd_replay_s, 0.0) << key;
    } else if (key.find("|cmaes|") != std::string::npos) {
      EXPECT_EQ(v.at("episodes").get<int>(), 300) << key;
      cmaes_s = v.at("seconds").get<double>();
      // CMA-ES draws its first population before its first episode: no seed shares any of it,
      // and its replay is not timed
      EXPECT_EQ(v.at("replay_s_per_episode").get<double>(), 0.0) << key;
    } else if (key.find("|ppo|") != std::string::npos) {
      EXPECT_EQ(v.at("episodes").get<int>(), 41) << key;
      ppo_s = v.at("seconds").get<double>();
    } else {
      EXPECT_NE(key.find("|boleap|"), std::string::npos) << key;
      EXPECT_EQ(v.at("episodes").get<int>(), 200) << key;
      boleap_s = v.at("seconds").get<double>();
    }
  }
  ASSERT_GT(cmaes_s, 0.0);
  ASSERT_GT(boleap_s, 0.0);
  ASSERT_GT(ppo_s, 0.0);
  const auto p = testing::run_harness(
      dir_, "plan " + grid + " --db " + path("p.sqlite") + " --runs-csv " + path("runs.csv"), cache);
  ASSERT_EQ(p.code, 0) << p.err;
  const std::string csv = testing::read_file(path("runs.csv"));
  // cmaes: its measured run itself (the plan writes 6 significant digits)
  EXPECT_NEAR(planned_seconds(csv, "cartpole3,cmaes,0,300,"), cmaes_s, 1e-5 * cmaes_s) << csv;
  // boleap: the measured 200 episodes carried to 300 by its model: the episodes at their calibrated
  // costs (the registry's share of gradient episodes), its own time the probe's plus the model's
  // growth from 200 to 300
  const auto costs = j.at("costs").begin().value();
  const double g = optimizer_entry("boleap").costs.gradient_share;
  EXPECT_GT(g, 0.0);
  EXPECT_LT(g, 1.0);
  const double per_episode = g * costs.at("gradient_s").get<double>() + (1.0 - g) * costs.at("forward_s").get<double>();
  const auto& own = optimizer_entry("boleap").costs.own_seconds;
  const double expected = per_episode * 300.0 + (boleap_s - per_episode * 200.0) + own(400, 300) - own(400, 200);
  EXPECT_NEAR(planned_seconds(csv, "cartpole3,boleap,0,300,"), expected, 1e-5 * expected) << csv;
  EXPECT_GT(own(400, 300), own(400, 200));
  // gd: seed 0 its measured run, seed 1 (a copy of seed 0) the replay of 300 episodes
  EXPECT_NEAR(planned_seconds(csv, "cartpole3,gd,0,300,"), gd_s, 1e-5 * gd_s) << csv;
  EXPECT_NEAR(planned_seconds(csv, "cartpole3,gd,1,300,"), 300.0 * gd_replay_s, 1e-5 * 300.0 * gd_replay_s) << csv;
  // ppo: its measured seconds per episode (acting, learning, the env) over the budget
  EXPECT_NEAR(planned_seconds(csv, "cartpole3,ppo,0,300,"), ppo_s / 41.0 * 300.0, 1e-5 * ppo_s * 300.0 / 41.0) << csv;
  // a longer budget: cmaes is timed again over the whole of it, and the cache keeps both
  ASSERT_EQ(
      testing::run_harness(dir_, "calibrate --env cartpole3 --optimizer cmaes --seeds 1 --budget 400", cache).code, 0);
  const auto j2 = nlohmann::json::parse(testing::read_file(path("costs.json")));
  EXPECT_EQ(j2.at("runs").size(), 5u) << j2.dump();
}

TEST_F(PlanFromDatabase, CalibrationTimesShortRunsInRoundsAcrossThePairsAsAGridRunsThem) {
  // the cache of this test alone (CostModel reads $DSB_COST_CACHE)
  const std::string cache = path("rounds.json");
  ASSERT_EQ(setenv("DSB_COST_CACHE", cache.c_str(), 1), 0);
  std::vector<RunSpec> grid;
  for (const auto& [env, opt] : {std::pair<std::string, std::string>{"sphere-10", "random"}, {"branin", "gd"}}) {
    GridRequest one;
    one.envs = {env};
    one.optimizers = {opt};
    one.budget = 50;
    for (RunSpec& spec : expand_grid(one)) grid.push_back(std::move(spec));
  }
  const GridPlan plan = plan_grid(grid, {}, "0.1.0");
  ASSERT_EQ(plan.pending.size(), 2u);
  CostModel costs;
  for (const PlannedRun& run : plan.pending) costs.calibrate(run.spec);
  for (const PlannedRun& run : plan.pending) ASSERT_TRUE(costs.probes(run)) << run.spec.env;
  std::vector<std::string> started;
  int rounds = 0;
  costs.calibrate_runs(
      plan.pending, time_probe, [&](const PlannedRun& run) { started.push_back(run.spec.env); },
      [&] {
        // after the first round every pair has been timed once: a pair's repeats come after the
        // other pairs' runs, not back to back
        if (++rounds == 1) {
          for (const PlannedRun& run : plan.pending) EXPECT_TRUE(costs.probed(run).has_value()) << run.spec.env;
        }
      });
  unsetenv("DSB_COST_CACHE");
  EXPECT_EQ(started, (std::vector<std::string>{"sphere-10", "branin"}));
  // 50 episodes of a 10-D or 2-D function take well under kProbeRepeatSeconds / kProbeRepeatsMax:
  // each pair is repeated, up to kProbeRepeatsMax rounds
  EXPECT_GT(rounds, 1);
  EXPECT_LE(rounds, kProbeRepeatsMax);
  for (const PlannedRun& run : plan.pending) {
    const auto p = costs.probed(run);
    ASSERT_TRUE(p.has_value());
    EXPECT_EQ(p->episodes, 50);
    EXPECT_GT(p->seconds, 0.0);
  }
  // gd never draws: its replay is timed; random draws before its first episode: not
  EXPECT_GT(costs.probed(plan.pending[1])->replay_s_per_episode, 0.0);
  EXPECT_EQ(costs.probed(plan.pending[0])->replay_s_per_episode, 0.0);
}

TEST(ProbeRepeats, AShortOrNoisyProbeIsTimedThreeTimesALongOneOnce) {
  EXPECT_FALSE(probe_timed_enough(0, 0.0));
  // a 50-ms run: until 0.2 s in all (4 timings)
  EXPECT_FALSE(probe_timed_enough(3, 0.15));
  EXPECT_TRUE(probe_timed_enough(4, 0.2));
  // a 0.1-ms run: nine timings at most
  EXPECT_FALSE(probe_timed_enough(8, 0.0008));
  EXPECT_TRUE(probe_timed_enough(9, 0.0009));
  // a 2-s GP run: three timings, the median kept (one timing alone was 1.59 s against 1.90-2.35)
  EXPECT_FALSE(probe_timed_enough(1, 2.0));
  EXPECT_FALSE(probe_timed_enough(2, 4.0));
  EXPECT_TRUE(probe_timed_enough(3, 6.0));
  // a 6-s run: two (12 s in all); a 30-s RL probe: one
  EXPECT_FALSE(probe_timed_enough(1, 6.0));
  EXPECT_TRUE(probe_timed_enough(2, 12.0));
  EXPECT_TRUE(probe_timed_enough(1, 30.0));
}

TEST_F(PlanFromDatabase, ACalibrationBelongsToTheBuildThatMadeIt) {
  const std::string cache = "DSB_COST_CACHE=" + path("costs.json");
  const std::string grid = "--env cartpole3 --optimizer cmaes --seeds 1 --budget 50";
  ASSERT_EQ(testing::run_harness(dir_, "calibrate " + grid, cache).code, 0);
  const auto plan = [&] { return testing::run_harness(dir_, "plan " + grid + " --db " + path("p.sqlite"), cache); };
  const auto mine = plan();
  ASSERT_EQ(mine.code, 0) << mine.err;
  EXPECT_NE(mine.out.find("measured on this machine for 1 of 1 envs"), std::string::npos) << mine.out;
  // the same cache as an older binary would have left it: every key's build field (the third
  // field: version+commit) another one's
  auto j = nlohmann::json::parse(testing::read_file(path("costs.json")));
  for (const char* table : {"costs", "runs"}) {
    nlohmann::json moved = nlohmann::json::object();
    for (const auto& [key, v] : j.at(table).items()) {
      std::vector<std::string> fields;
      std::istringstream in(key);
      for (std::string f; std::getline(in, f, '|');) fields.push_back(f);
      const std::size_t build = std::string(table) == "costs" ? 2 : 5;  // runs: env|hash|opt|hash|episodes|build|cpu
      ASSERT_GT(fields.size(), build + 1) << key;
      // version+commit: "0.1.0+1b6c2f752ac9" (or with "-dirty")
      const auto plus = fields[build].find('+');
      ASSERT_NE(plus, std::string::npos) << key;
      EXPECT_GE(fields[build].size() - plus - 1, 7u) << key;
      fields[build] = fields[build].substr(0, plus) + "+000000000000";
      std::string other;
      for (std::size_t i = 0; i < fields.size(); ++i) other += (i ? "|" : "") + fields[i];
      moved[other] = v;
    }
    j[table] = moved;
  }
  {
    std::ofstream out(path("costs.json"));
    out << j.dump(2);
  }
  const auto theirs = plan();
  ASSERT_EQ(theirs.code, 0) << theirs.err;
  EXPECT_NE(theirs.out.find("measured on this machine for 0 of 1 envs"), std::string::npos) << theirs.out;
  EXPECT_NE(theirs.out.find("1 of them were measured by another build of the harness"), std::string::npos)
      << theirs.out;
}

TEST(PlanCosts, BoLeapsGpIsFittedOnItsDesignAndAfterEveryLeapThatLeavesBudget) {
  // cartpole3: a design of 20 points, then fits at 120, 220, ..., 920 for 1,000 episodes
  EXPECT_EQ(boleap_fits(400, 1000, 100), 10);
  EXPECT_EQ(boleap_fits(400, 200, 100), 2);
  EXPECT_EQ(boleap_fits(400, 10, 100), 1);
  // one fit at n = 20: evaluations (70 + 0.17 n) x (n^3 and n^2 d terms)
  const double n = 20.0, evaluations = kBoLeapEvaluationsBase + kBoLeapEvaluationsPerPoint * n;
  EXPECT_DOUBLE_EQ(boleap_own_seconds(400, 20, 100),
                   evaluations * (kBoSecondsPerN3 * n * n * n + kBoSecondsPerN2D * n * n * 400.0));
  EXPECT_GT(boleap_own_seconds(400, 1000, 100), boleap_own_seconds(10, 1000, 100));
}

TEST(PlanCosts, NoOptimizerIsNamedInTheHarness) {
  // their costs, families and seed use come from the registry: harness/ code names none of them
  for (const auto& entry : std::filesystem::recursive_directory_iterator(std::string(DSB_SOURCE_DIR) + "/harness")) {
    if (!entry.is_regular_file()) continue;
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
