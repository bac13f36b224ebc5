// Sharing across seeds (harness/store/store.hpp, Store::begin_run): a run replays the episodes an
// earlier seed's run of its group simulated before its optimizer's first draw. Checked through
// the real `harness` program on real databases: a grid gives the same database with and without
// --no-sharing, bit for bit; the database says which episodes were shared and from which seed;
// a run whose optimizer draws at once shares nothing; an interrupted sharing run resumes to the
// same evals; `plan` counts shared episodes as free; and below the CLI, the first draw is found
// where the optimizer makes it.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "harness/run/budget.hpp"
#include "support/harness_process.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

using testing::rows;
using testing::scalar;

class Sharing : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args, const std::string& env_prefix = "") {
    return testing::run_harness(dir_, args, env_prefix);
  }
  // every episode of every run, bit for bit, and the runs' results (not timings, not sharing)
  static std::vector<std::string> results(const std::string& db) {
    auto r = rows(db,
                  "SELECT env, optimizer, seed, status, episodes, failed_episodes, best_loss, best_x, "
                  "seed_free_episodes, seed_free_calls, diagnostics FROM runs ORDER BY env, optimizer, seed");
    for (const auto& e :
         rows(db,
              "SELECT r.env, r.optimizer, r.seed, e.episode, e.loss, e.best_loss, e.used_grad, e.failed, e.metric "
              "FROM evals e JOIN runs r USING(run_id) ORDER BY r.env, r.optimizer, r.seed, e.episode"))
      r.push_back(e);
    return r;
  }
};

const std::string kGrid =
    "--env bounce,rastrigin-10,cartpole1 --optimizer gd,nlopt-lbfgs,nlopt-bobyqa,nlopt-direct-l,random "
    "--seeds 3 --budget 120 --jobs 2 --quiet";

TEST_F(Sharing, AGridGivesTheSameDatabaseWithAndWithoutSharing) {
  const auto shared = harness(kGrid + " --db " + path("shared.sqlite"));
  ASSERT_EQ(shared.code, 0) << shared.err;
  const auto simulated = harness(kGrid + " --no-sharing --db " + path("simulated.sqlite"));
  ASSERT_EQ(simulated.code, 0) << simulated.err;
  EXPECT_EQ(results(path("shared.sqlite")), results(path("simulated.sqlite")));
  // the result tables are the same file
  ASSERT_EQ(harness("export --db " + path("shared.sqlite") + " --out " + path("shared.csv")).code, 0);
  ASSERT_EQ(harness("export --db " + path("simulated.sqlite") + " --out " + path("simulated.csv")).code, 0);
  EXPECT_EQ(testing::read_file(path("shared.csv")), testing::read_file(path("simulated.csv")));
  // sharing happened, and the harness said so; without it nothing was shared
  EXPECT_NE(shared.err.find("episodes from an earlier seed's run"), std::string::npos) << shared.err;
  EXPECT_EQ(simulated.err.find("episodes from an earlier seed's run"), std::string::npos) << simulated.err;
  EXPECT_EQ(scalar(path("simulated.sqlite"), "SELECT sum(shared_episodes) FROM runs"), "0");
  EXPECT_NE(scalar(path("shared.sqlite"), "SELECT sum(shared_episodes) FROM runs"), "0");
  // both keep the leads' seed-free journals, for a later grid to share
  EXPECT_EQ(scalar(path("simulated.sqlite"), "SELECT count(*) FROM prefix"),
            scalar(path("shared.sqlite"), "SELECT count(*) FROM prefix"));
}

TEST_F(Sharing, TheDatabaseSaysWhichEpisodesWereSharedAndFromWhere) {
  ASSERT_EQ(harness(kGrid + " --db " + path("s.sqlite")).code, 0);
  const std::string db = path("s.sqlite");
  // gd never draws: seeds 1 and 2 are seed 0's run, replayed whole
  EXPECT_EQ(
      rows(db,
           "SELECT env, seed, seed_free_episodes, shared_episodes, shared_from_seed FROM runs WHERE "
           "optimizer='gd' ORDER BY env, seed"),
      (std::vector<std::string>{"bounce|0|120|0|NULL", "bounce|1|120|120|0", "bounce|2|120|120|0",
                                "cartpole1|0|120|0|NULL", "cartpole1|1|120|120|0", "cartpole1|2|120|120|0",
                                "rastrigin-10|0|120|0|NULL", "rastrigin-10|1|120|120|0", "rastrigin-10|2|120|120|0"}));
  // random draws before its first episode: nothing to share
  EXPECT_EQ(scalar(db,
                   "SELECT max(seed_free_episodes) || ' ' || max(shared_episodes) FROM runs WHERE "
                   "optimizer='random'"),
            "0 0");
  // the NLopt methods share exactly the episodes before the first restart's draw: the later
  // seeds' shared episodes are the lead's seed-free ones, and their own seed-free prefix agrees
  for (const auto& r : rows(db,
                            "SELECT f.env, f.optimizer, f.seed, f.shared_episodes, l.seed_free_episodes, "
                            "f.seed_free_episodes, f.shared_from_seed FROM runs f JOIN runs l ON l.env=f.env AND "
                            "l.optimizer=f.optimizer AND l.seed=0 WHERE f.optimizer LIKE 'nlopt-%' AND f.seed>0")) {
    const auto parts = [&] {
      std::vector<std::string> p;
      std::size_t a = 0;
      for (std::size_t b; (b = r.find('|', a)) != std::string::npos; a = b + 1) p.push_back(r.substr(a, b - a));
      p.push_back(r.substr(a));
      return p;
    }();
    EXPECT_EQ(parts[3], parts[4]) << r;  // shared = the lead's seed-free episodes
    EXPECT_EQ(parts[5], parts[4]) << r;  // the same prefix for every seed
    EXPECT_EQ(parts[6], std::stoi(parts[3]) > 0 ? "0" : "NULL") << r;
  }
  EXPECT_NE(scalar(db, "SELECT min(seed_free_episodes) FROM runs WHERE optimizer='nlopt-lbfgs'"), "0");
  // one kept prefix per group that has one, the journal of the lead's seed-free episodes
  EXPECT_EQ(scalar(db, "SELECT count(DISTINCT run_id) FROM prefix"),
            scalar(db, "SELECT count(*) FROM runs WHERE seed=0 AND seed_free_episodes > 0"));
  EXPECT_EQ(scalar(db,
                   "SELECT count(*) FROM runs r WHERE (SELECT count(*) FROM prefix p WHERE p.run_id=r.run_id) "
                   "NOT IN (0, r.seed_free_calls)"),
            "0");
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM replay"), "0");
}

TEST_F(Sharing, ALaterSeedOfAnEarlierGridSharesAndAnInterruptedSharingRunResumes) {
  const std::string one = "--env cartpole1 --optimizer gd,nlopt-lbfgs --budget 120 --jobs 1 --quiet";
  ASSERT_EQ(harness(one + " --seeds 3 --no-sharing --db " + path("ref.sqlite")).code, 0);
  // seed 0 in an earlier grid, seeds 1 and 2 later: they take seed 0's kept prefix
  ASSERT_EQ(harness(one + " --seeds 1 --db " + path("s.sqlite")).code, 0);
  const std::string lbfgs_free =
      scalar(path("s.sqlite"), "SELECT seed_free_episodes FROM runs WHERE optimizer='nlopt-lbfgs'");
  ASSERT_GT(std::stoi(lbfgs_free), 0);
  // stopped after episode FAULT of the first run to reach it (inside gd's shared run, or past lbfgs's
  // seed-free episodes): it commits, and the same command resumes it
  const int fault = std::stoi(lbfgs_free) + 5;
  ASSERT_LT(fault, 120);
  const auto stopped = harness(one + " --seeds 3 --db " + path("s.sqlite"),
                               "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=" + std::to_string(fault) +
                                   " DSB_FAULT_SIGNAL=15 DSB_FAULT_COMMIT_EVERY_EPISODE=1");
  EXPECT_EQ(stopped.code, 143) << stopped.err;
  EXPECT_EQ(scalar(path("s.sqlite"), "SELECT count(*) FROM runs WHERE status='running'"), "1");
  const auto resumed = harness(one + " --seeds 3 --db " + path("s.sqlite"));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(results(path("s.sqlite")), results(path("ref.sqlite")));
  EXPECT_EQ(rows(path("s.sqlite"),
                 "SELECT optimizer, seed, shared_episodes, shared_from_seed FROM runs WHERE seed>0 "
                 "ORDER BY optimizer, seed"),
            (std::vector<std::string>{"gd|1|120|0", "gd|2|120|0", "nlopt-lbfgs|1|" + lbfgs_free + "|0",
                                      "nlopt-lbfgs|2|" + lbfgs_free + "|0"}));
}

TEST_F(Sharing, PlanCountsSharedEpisodesAsFree) {
  const std::string grid =
      "plan --env cartpole1 --optimizer gd,random --seeds 5 --budget 1000 --db " + path("none.sqlite");
  const auto p = harness(grid);
  ASSERT_EQ(p.code, 0) << p.err;
  // gd's seeds 1-4 replay seed 0's whole run
  EXPECT_NE(p.out.find("sharing across seeds: 4 runs take about 4000 episodes"), std::string::npos) << p.out;
  const auto n = harness(grid + " --no-sharing");
  ASSERT_EQ(n.code, 0) << n.err;
  EXPECT_EQ(n.out.find("sharing across seeds"), std::string::npos) << n.out;
}

TEST(FirstDraw, TheSeedFreePrefixEndsWhereTheOptimizerFirstDraws) {
  const auto env = make_env("sphere-3");
  BudgetedObjective f(*env, 10);
  Rng rng(7);
  f.watch_draws(&rng);
  const std::vector<double> x = {0.1, 0.2, 0.3};
  f.value(x);
  f.value(x);
  EXPECT_FALSE(f.seed_free_prefix().drew);
  EXPECT_EQ(f.seed_free_prefix().episodes, 2);
  rng.skip_u64();  // a value no result depends on: not a use of the seed
  f.value(x);
  EXPECT_FALSE(f.seed_free_prefix().drew);
  rng.uniform();  // the first draw: what came before it is the prefix
  f.value(x);
  f.value(x);
  const SeedFreePrefix p = f.seed_free_prefix();
  EXPECT_TRUE(p.drew);
  EXPECT_EQ(p.episodes, 3);
  EXPECT_EQ(rng.draws(), 1u);
}

TEST(FirstDraw, SkipAdvancesTheStreamLikeADraw) {
  Rng a(11), b(11);
  a.next_u64();
  b.skip_u64();
  EXPECT_EQ(a.next_u64(), b.next_u64());
  EXPECT_EQ(a.draws(), 2u);
  EXPECT_EQ(b.draws(), 1u);
}

}  // namespace
}  // namespace dsb
