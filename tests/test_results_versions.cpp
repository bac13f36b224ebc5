// Results versions (harness/core/results_versions.hpp, docs/database.md "Results versions"): every stored
// run names the versions of the code that made it, and a binary never resumes, counts as done,
// exports or checks as its own a run of other versions. The database is rewritten the way an
// older binary would have left it (its runs' versions set to other numbers, or to none as a
// schema-4 file has), through the real program on real files.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "harness/store/result_table.hpp"
#include "harness/core/results_versions.hpp"
#include "support/harness_process.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using testing::read_file;
using testing::scalar;

const std::string kGrid = "--env sphere-2,branin --optimizer random,cmaes --seeds 2 --jobs 1 --quiet";

class ResultsVersionsTest : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args, const std::string& env_prefix = "") {
    return testing::run_harness(dir_, args, env_prefix);
  }
  // a database with the 8 runs of kGrid at budget 12 done, and one run of budget 30 stopped by
  // SIGTERM after 5 episodes (left 'running' with its journal: resumable by this binary)
  std::string mixed_db() {
    const std::string db = path("v.sqlite");
    EXPECT_EQ(harness(kGrid + " --budget 12 --db " + db).code, 0);
    const auto stopped = harness("--env sphere-2 --optimizer cmaes --seeds 1 --budget 30 --quiet --db " + db,
                                 "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=5 DSB_FAULT_SIGNAL=15");
    EXPECT_EQ(stopped.code, 143) << stopped.err;
    EXPECT_EQ(scalar(db, "SELECT status || ' ' || (episodes >= 5) FROM runs WHERE budget = 30"), "running 1");
    return db;
  }
};

TEST(ResultsVersions, TextRoundTripsAndTheCurrentOnesAreThoseOfTheRegistrations) {
  const ResultsVersions v{2, 1, 3};
  EXPECT_EQ(v.text(), "env 2, optimizer 1, run 3");
  EXPECT_EQ(parse_results_versions(v.text()), v);
  EXPECT_EQ(parse_results_versions(""), ResultsVersions{});
  EXPECT_THROW(parse_results_versions("env 2, optimizer 1"), std::invalid_argument);
  EXPECT_THROW(parse_results_versions("env 02, optimizer 1, run 3"), std::invalid_argument);
  EXPECT_EQ(stored_results_versions("garbage"), ResultsVersions{});
  const ResultsVersions now = current_results_versions("plb-pinch-h5", "boleap");
  EXPECT_GE(now.env, 1);
  EXPECT_GE(now.optimizer, 1);
  EXPECT_EQ(now.run, kRunCodeResultsVersion);
  // a variant has its env's version, an external optimizer the adapter's
  EXPECT_EQ(current_results_versions("plb-pinch", "boleap"), now);
  EXPECT_EQ(current_results_versions("sphere-2", "ext:mine").optimizer, kExtResultsVersion);
  EXPECT_EQ(current_results_versions("no-such-env", "random").env, 0);
  EXPECT_EQ(stale_reason("sphere-2", "random", current_results_versions("sphere-2", "random")), "");
  EXPECT_EQ(stale_reason("sphere-2", "random", {}), "made before results versions (a database of schema 4 or older)");
  const ResultsVersions older{now.env, now.optimizer - 1, now.run};
  EXPECT_EQ(stale_reason("plb-pinch", "boleap", older),
            "optimizer boleap version " + std::to_string(now.optimizer - 1) + ", this binary's " +
                std::to_string(now.optimizer));
}

TEST_F(ResultsVersionsTest, ADatabaseOfOtherVersionsResumesNothingAndEveryCommandSaysSo) {
  const std::string db = mixed_db();
  ASSERT_EQ(harness("export --db " + db + " --out " + path("before.csv")).code, 0);
  // an older binary: another optimizer version for cmaes, no versions at all for random
  const ResultsVersions now = current_results_versions("sphere-2", "cmaes");
  const ResultsVersions older{now.env, now.optimizer + 1, now.run};
  testing::execute(db, "UPDATE runs SET results_versions='" + older.text() + "' WHERE optimizer='cmaes'");
  testing::execute(db, "UPDATE runs SET results_versions='' WHERE optimizer='random'");
  const auto stale_rows = testing::rows(db, "SELECT * FROM runs ORDER BY run_id");
  const auto stale_evals = testing::rows(db, "SELECT * FROM evals ORDER BY run_id, episode");

  // plan: nothing done, every stored run stale, by env, optimizer and reason
  const auto plan = harness("plan " + kGrid + " --budget 12 --db " + db);
  EXPECT_EQ(plan.code, 0) << plan.err;
  EXPECT_NE(plan.out.find("8 runs in the grid; 0 already done"), std::string::npos) << plan.out;
  EXPECT_NE(plan.out.find("stale: 9 stored runs of this grid's envs and optimizers (8 done, 1 unfinished)"),
            std::string::npos)
      << plan.out;
  EXPECT_NE(plan.out.find("sphere-2 / cmaes: 2 done, 1 unfinished: optimizer cmaes version " +
                          std::to_string(older.optimizer) + ", this binary's " + std::to_string(now.optimizer)),
            std::string::npos)
      << plan.out;
  EXPECT_NE(plan.out.find("branin / random: 2 done, 0 unfinished: made before results versions"), std::string::npos)
      << plan.out;

  // export and check leave them out and say so; --include-stale shows them, marked
  const auto ex = harness("export --db " + db + " --out " + path("now.csv"));
  EXPECT_EQ(ex.code, 0) << ex.err;
  EXPECT_EQ(read_file(path("now.csv")), std::string(kResultTableHeader) + "\n");
  EXPECT_NE(ex.err.find("left out 8 stale done runs"), std::string::npos) << ex.err;
  const auto all = harness("export --db " + db + " --include-stale --out " + path("all.csv"));
  EXPECT_EQ(all.code, 0) << all.err;
  EXPECT_NE(read_file(path("all.csv")).find(std::string(kResultTableHeader) + ",stale\n"), std::string::npos);
  EXPECT_NE(read_file(path("all.csv")).find(",1\n"), std::string::npos);
  const auto ioh = harness("export --db " + db + " --format ioh --out " + path("ioh"));
  EXPECT_NE(ioh.err.find("left out 8 stale runs"), std::string::npos) << ioh.err;
  const auto check = harness("check --db " + db + " --baseline " + path("before.csv"));
  EXPECT_EQ(check.code, 1);
  EXPECT_NE(check.out.find("left out 8 stale done runs"), std::string::npos) << check.out;
  EXPECT_NE(check.out.find("0 rows equal"), std::string::npos) << check.out;

  // the grid resumes nothing of them: all 8 run again beside them, the stopped one starts over
  const auto again = harness(kGrid + " --budget 12 --db " + db);
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.err.find("8 runs in the grid: 0 already done, 8 done now"), std::string::npos) << again.err;
  const auto resumed = harness("--env sphere-2 --optimizer cmaes --seeds 1 --budget 30 --quiet --db " + db);
  EXPECT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(resumed.err.find("resumed"), std::string::npos) << resumed.err;
  const std::string current = now.text();
  EXPECT_EQ(
      scalar(db, "SELECT count(*) FROM runs WHERE status='done' AND budget=30 AND results_versions='" + current + "'"),
      "1");
  // the stale runs are byte for byte as they were
  EXPECT_EQ(testing::rows(db, "SELECT * FROM runs WHERE run_id <= 9 ORDER BY run_id"), stale_rows);
  EXPECT_EQ(testing::rows(db, "SELECT * FROM evals WHERE run_id <= 9 ORDER BY run_id, episode"), stale_evals);
  // and the current runs' table equals the first grid's, versions and all
  ASSERT_EQ(harness("export --db " + db + " --out " + path("after.csv")).code, 0);
  const auto recheck = harness("check --db " + db + " --baseline " + path("before.csv"));
  EXPECT_EQ(recheck.code, 1);  // the budget-30 run is new: added rows, nothing changed
  EXPECT_NE(recheck.out.find(" 0 changed, 0 missing"), std::string::npos) << recheck.out;
}

// `harness report` (reports/make_report.py, told this binary's results versions by its `harness
// list`) leaves the runs an older binary made out of every table and says how many and why;
// --include-stale shows them, each an optimizer of its own, never pooled with the current runs. A
// schema-4 file (no runs.results_versions) is read as it is: every run stale, the file unchanged.
TEST_F(ResultsVersionsTest, TheReportLeavesStaleRunsOutAndShowsThemWhenAsked) {
  const std::string db = path("r.sqlite");
  ASSERT_EQ(harness(kGrid + " --budget 12 --db " + db).code, 0);
  // random's 4 runs as a binary from before versions left them; cmaes's 4 stay current
  testing::execute(db, "UPDATE runs SET results_versions='' WHERE optimizer='random'");
  const std::string made_before = "made before results versions (a database of schema 4 or older)";

  const auto left_out = harness("report --db " + db + " --out " + path("rep"));
  ASSERT_EQ(left_out.code, 0) << left_out.err;
  const std::string page = read_file(path("rep/index.html"));
  EXPECT_NE(page.find("Left out: 4 stale run(s) (4 done, 0 unfinished)"), std::string::npos) << page;
  EXPECT_NE(page.find("branin / random: 2 done, 0 unfinished: " + made_before), std::string::npos);
  EXPECT_NE(page.find("sphere-2 / random: 2 done, 0 unfinished: " + made_before), std::string::npos);
  const std::string finals = read_file(path("rep/final_sphere-2.csv"));
  EXPECT_NE(finals.find("\nsphere-2,12,cmaes,2,"), std::string::npos) << finals;
  EXPECT_EQ(finals.find("random"), std::string::npos) << finals;
  EXPECT_EQ(read_file(path("rep/stale_runs.csv")),
            "env,optimizer,results_versions,reason,done,unfinished,shown_as\n"
            "branin,random,,made before results versions (a database of schema 4 or older),2,0,\n"
            "sphere-2,random,,made before results versions (a database of schema 4 or older),2,0,\n");

  const auto shown = harness("report --include-stale --db " + db + " --out " + path("all"));
  ASSERT_EQ(shown.code, 0) << shown.err;
  EXPECT_NE(read_file(path("all/index.html")).find("Shown: 4 stale run(s) (4 done, 0 unfinished)"), std::string::npos);
  const std::string all = read_file(path("all/final_sphere-2.csv"));
  EXPECT_NE(all.find("\nsphere-2,12,cmaes,2,"), std::string::npos) << all;
  EXPECT_NE(all.find("\nsphere-2,12,random-stale-unversioned,2,"), std::string::npos) << all;

  // schema 4: the runs table rebuilt without results_versions, as a file of version 4 has it
  testing::execute(db,
                   "CREATE TABLE runs4 AS SELECT run_id, env, optimizer, seed, budget, env_config_hash, "
                   "opt_config_hash, rng_seed, status, episodes, failed_episodes, best_loss, best_x, wall_s, error, "
                   "started_at, finished_at, harness_version, git_sha, host, diagnostics, seed_free_episodes, "
                   "seed_free_calls, shared_episodes, shared_from_seed FROM runs; DROP TABLE runs; "
                   "ALTER TABLE runs4 RENAME TO runs; UPDATE meta SET value='4' WHERE key='schema_version'");
  ASSERT_EQ(scalar(db, "SELECT count(*) FROM pragma_table_info('runs') WHERE name='results_versions'"), "0");
  const std::string before = read_file(db);
  const auto old = harness("report --db " + db + " --out " + path("v4"));
  ASSERT_EQ(old.code, 0) << old.err;
  const std::string v4 = read_file(path("v4/index.html"));
  EXPECT_NE(v4.find("Left out: 8 stale run(s) (8 done, 0 unfinished)"), std::string::npos) << v4;
  EXPECT_NE(v4.find("sphere-2 / cmaes: 2 done, 0 unfinished: " + made_before), std::string::npos);
  const auto old_all = harness("report --include-stale --db " + db + " --out " + path("v4all"));
  ASSERT_EQ(old_all.code, 0) << old_all.err;
  EXPECT_NE(read_file(path("v4all/final_branin.csv")).find("\nbranin,12,cmaes-stale-unversioned,2,"),
            std::string::npos);
  EXPECT_EQ(read_file(db), before);  // read, never changed
}

TEST_F(ResultsVersionsTest, MergeKeepsTheVersionsApart) {
  const std::string a = path("a.sqlite"), b = path("b.sqlite");
  ASSERT_EQ(harness(kGrid + " --budget 12 --db " + a).code, 0);
  ASSERT_EQ(harness(kGrid + " --budget 12 --db " + b).code, 0);
  testing::execute(b, "UPDATE runs SET results_versions=''");  // the same runs, from before versions
  const auto m = harness("merge --into " + path("m.sqlite") + " " + a + " " + b);
  ASSERT_EQ(m.code, 0) << m.err;
  EXPECT_EQ(scalar(path("m.sqlite"), "SELECT count(*) FROM runs"), "16");
  EXPECT_EQ(scalar(path("m.sqlite"), "SELECT count(*) FROM runs WHERE results_versions=''"), "8");
}

}  // namespace
}  // namespace dsb
