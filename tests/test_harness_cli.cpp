// The `harness` program end to end, as a user runs it: the done-when grid, bit-identical evals
// whatever --jobs, SIGKILL part-way then resume, bad input (exit 2, one line naming the value,
// the database unchanged), eval/list/gradcheck output.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>
#include <tuple>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>

#include "envs/core/gradient_check.hpp"
#include "envs/registry.hpp"
#include "harness/plan/grid.hpp"
#include "optimizers/registry.hpp"
#include "support/harness_process.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

using Result = testing::HarnessResult;

class HarnessCli : public dsb::testing::TempDirTest {
 protected:
  // runs the harness through the shell; env_prefix may set variables
  Result harness(const std::string& args, const std::string& env_prefix = "") {
    return testing::run_harness(dir_, args, env_prefix);
  }
  static std::string read(const fs::path& p) { return testing::read_file(p); }
  std::string db(const std::string& name) { return path(name); }
};

using testing::EvalKey;

// every eval's loss by (env, optimizer, seed, budget, episode); NULL (failed) as NaN
std::map<EvalKey, double> read_evals(const std::string& path) { return testing::stored_losses(path); }

std::string scalar(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* q = nullptr;
  sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr);
  std::string v = sqlite3_step(q) == SQLITE_ROW && sqlite3_column_text(q, 0)
      ? reinterpret_cast<const char*>(sqlite3_column_text(q, 0))
      : "";
  sqlite3_finalize(q);
  sqlite3_close(db);
  return v;
}

using testing::wait_until;

void expect_same_evals(const std::map<EvalKey, double>& a, const std::map<EvalKey, double>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [k, v] : a) {
    const auto it = b.find(k);
    ASSERT_NE(it, b.end());
    // bit-identical (NaN matches NaN)
    EXPECT_TRUE(std::memcmp(&v, &it->second, sizeof v) == 0 || (std::isnan(v) && std::isnan(it->second)))
        << std::get<0>(k) << "/" << std::get<1>(k) << " seed " << std::get<2>(k) << " episode " << std::get<4>(k)
        << ": " << v << " vs " << it->second;
  }
}

const std::string kGrid =
    "--env cartpole3,rosenbrock-10,branin --optimizer random,gd,rand-descents,cmaes --seeds 2 --budget 60 --quiet";

TEST_F(HarnessCli, DoneWhenGridStoresSixHundredEvals) {
  const auto r = harness(
      "--env cartpole3,rosenbrock-10 --optimizer random,gd,cmaes --seeds 2 "
      "--budget 50 --db " +
      db("x.sqlite"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(scalar(db("x.sqlite"), "SELECT count(*) FROM evals"), "600");
  EXPECT_EQ(scalar(db("x.sqlite"), "SELECT count(*) FROM runs WHERE status='done' AND episodes=50"), "12");
  EXPECT_NE(r.err.find("runs 12/12"), std::string::npos) << r.err;  // the progress line
  // a second start finds everything done and changes nothing
  const auto again = harness(
      "--env cartpole3,rosenbrock-10 --optimizer random,gd,cmaes --seeds 2 "
      "--budget 50 --db " +
      db("x.sqlite"));
  ASSERT_EQ(again.code, 0);
  EXPECT_NE(again.err.find("12 already done, 0 done now"), std::string::npos) << again.err;
  EXPECT_EQ(scalar(db("x.sqlite"), "SELECT count(*) FROM evals"), "600");
}

TEST_F(HarnessCli, EvalsAreBitIdenticalWhateverTheNumberOfJobs) {
  ASSERT_EQ(harness(kGrid + " --jobs 1 --db " + db("j1.sqlite")).code, 0);
  ASSERT_EQ(harness(kGrid + " --jobs 2 --db " + db("j2.sqlite")).code, 0);
  const auto a = read_evals(db("j1.sqlite")), b = read_evals(db("j2.sqlite"));
  EXPECT_EQ(a.size(), 3u * 4u * 2u * 60u);
  expect_same_evals(a, b);
}

TEST_F(HarnessCli, GridKilledPartWayAndResumedEqualsTheUninterruptedGrid) {
  ASSERT_EQ(harness(kGrid + " --jobs 2 --db " + db("full.sqlite")).code, 0);
  // SIGKILL the harness three times at different points (after 150, 400 and 300 episodes in
  // that start), resuming each time; then let it finish
  int kills = 0;
  for (const char* k : {"150", "400", "300"}) {
    const auto r = harness(kGrid + " --jobs 1 --db " + db("resumed.sqlite"),
                           std::string("DSB_FAULT_INJECTION=kill-after-episodes DSB_FAULT_KILL_AFTER_EPISODES=") + k);
    kills += r.code == 128 + SIGKILL;
    // the killed run is left 'running' and does not count as done
    EXPECT_EQ(scalar(db("resumed.sqlite"), "SELECT count(*) FROM runs WHERE status='running'"), "1");
  }
  EXPECT_EQ(kills, 3);
  const auto final_run = harness(kGrid + " --jobs 2 --db " + db("resumed.sqlite"));
  ASSERT_EQ(final_run.code, 0) << final_run.err;
  EXPECT_EQ(scalar(db("resumed.sqlite"), "SELECT count(*) FROM runs WHERE status!='done'"), "0");
  expect_same_evals(read_evals(db("full.sqlite")), read_evals(db("resumed.sqlite")));
}

TEST_F(HarnessCli, ExternalSigkillDuringALongRunLeavesNothingHalfDone) {
  // a run long enough to be killed from outside while it is computing: started in the
  // background, killed once the database shows its first run 'running' (polled, no sleep that a
  // loaded machine could outlast)
  const std::string grid = "--env cartpole3 --optimizer cmaes --seeds 3 --budget 20000 --jobs 1 --quiet";
  const pid_t pid = testing::start_harness(grid + " --db " + db("k.sqlite"));
  ASSERT_GE(pid, 0);
  const bool started = wait_until(db("k.sqlite"), "SELECT count(*) FROM runs WHERE status='running'", "1", pid,
                                  std::chrono::seconds(120));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(started) << "no run row 'running' appeared (the harness exited or took over 120 s)";
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the harness ended before the kill";
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT count(*) FROM runs WHERE status='running'"), "1");
  // what the running run committed is a whole prefix: episodes 0..n-1, counted in runs.episodes,
  // with the journal that replays it
  const std::string running = "(SELECT run_id FROM runs WHERE status='running')";
  const std::string n = scalar(db("k.sqlite"), "SELECT count(*) FROM evals WHERE run_id=" + running);
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT episodes FROM runs WHERE status='running'"), n);
  if (n != "0") {
    EXPECT_EQ(scalar(db("k.sqlite"), "SELECT max(episode) + 1 FROM evals WHERE run_id=" + running), n);
    EXPECT_NE(scalar(db("k.sqlite"), "SELECT count(*) FROM replay WHERE run_id=" + running), "0");
  }
  // runs that are done have all their evals and no journal
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT count(*) FROM evals JOIN runs USING(run_id) WHERE status='done'"),
            std::to_string(std::stoi(scalar(db("k.sqlite"), "SELECT count(*) FROM runs WHERE status='done'")) * 20000));
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT count(*) FROM replay JOIN runs USING(run_id) WHERE status='done'"), "0");
}

TEST_F(HarnessCli, SigtermMidRunCommitsAndTheResumedRunEqualsTheUninterruptedOne) {
  // one run per kind of objective call: batches (random), gradients (gd), one at a time (cmaes),
  // RL decisions (ppo); the run is stopped after its 25th episode and resumed by replay
  for (const std::string opt : {"random", "gd", "cmaes", "ppo"}) {
    const std::string grid = "--env cartpole1 --optimizer " + opt + " --seeds 1 --budget 60 --jobs 1 --quiet --db ";
    ASSERT_EQ(harness(grid + db(opt + "-full.sqlite")).code, 0) << opt;
    const auto stopped = harness(grid + db(opt + ".sqlite"),
                                 "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=25 DSB_FAULT_SIGNAL=15");
    EXPECT_EQ(stopped.code, 143) << opt << ": " << stopped.err;
    EXPECT_NE(stopped.err.find("stopped by SIGTERM: 1 runs in progress committed"), std::string::npos) << stopped.err;
    EXPECT_NE(stopped.err.find("run the same command again to resume"), std::string::npos) << stopped.err;
    const std::string committed = scalar(db(opt + ".sqlite"), "SELECT episodes FROM runs WHERE status='running'");
    ASSERT_FALSE(committed.empty()) << opt;
    EXPECT_GE(std::stoi(committed), 25) << opt;
    EXPECT_LT(std::stoi(committed), 60) << opt;
    EXPECT_EQ(scalar(db(opt + ".sqlite"), "SELECT count(*) FROM evals"), committed) << opt;
    EXPECT_NE(scalar(db(opt + ".sqlite"), "SELECT count(*) FROM replay"), "0") << opt;
    // the CPU seconds it spent so far are stored with the stop's commit, and the resume adds its own
    const double cpu_stopped = std::stod(scalar(db(opt + ".sqlite"), "SELECT cpu_s FROM runs"));
    EXPECT_GT(cpu_stopped, 0.0) << opt;

    const auto resumed = harness(grid + db(opt + ".sqlite"));
    ASSERT_EQ(resumed.code, 0) << opt << ": " << resumed.err;
    EXPECT_NE(resumed.err.find("resumed 1 interrupted runs, " + committed + " of their episodes replayed"),
              std::string::npos)
        << opt << ": " << resumed.err;
    expect_same_evals(read_evals(db(opt + "-full.sqlite")), read_evals(db(opt + ".sqlite")));
    EXPECT_EQ(scalar(db(opt + ".sqlite"), "SELECT count(*) FROM replay"), "0") << opt;  // dropped when done
    EXPECT_GT(std::stod(scalar(db(opt + ".sqlite"), "SELECT cpu_s FROM runs")), cpu_stopped) << opt;
  }
}

TEST_F(HarnessCli, EveryRunStoresTheCpuSecondsOfItsThreadAndItsThreadTeam) {
  // two runs side by side in one process are told apart: each its own worker thread's CPU, which
  // cannot exceed the run's wall (the CPU is read a little before and after the wall's clock: 50 ms)
  ASSERT_EQ(harness(kGrid + " --jobs 2 --db " + db("cpu.sqlite")).code, 0);
  EXPECT_EQ(scalar(db("cpu.sqlite"), "SELECT count(*) FROM runs WHERE cpu_s > 0 AND cpu_s <= wall_s + 0.05"),
            scalar(db("cpu.sqlite"), "SELECT count(*) FROM runs"));
  // with a thread team the workers' CPU over the run is added (ThreadTeam::workers_cpu_seconds,
  // test_parallel; NULL until 2026-12-06): the MPM engine gives each of 2 threads half of each
  // substep, so the run's CPU is its one-thread CPU again (0.30 s and 0.30 s here; the caller's
  // thread alone 0.14 s), and at most two threads' worth of its wall
  const std::string mpm = "--env fluid-h5 --optimizer cmaes --seeds 1 --budget 6 --quiet --db ";
  ASSERT_EQ(harness(mpm + db("one.sqlite") + " --threads 1").code, 0);
  ASSERT_EQ(harness(mpm + db("team.sqlite") + " --threads 2").code, 0);
  const double one = std::stod(scalar(db("one.sqlite"), "SELECT cpu_s FROM runs"));
  const double team = std::stod(scalar(db("team.sqlite"), "SELECT cpu_s FROM runs"));
  EXPECT_GE(team, 0.8 * one) << "one thread " << one;
  EXPECT_EQ(scalar(db("team.sqlite"), "SELECT count(*) FROM runs WHERE cpu_s <= 2 * wall_s + 0.1"), "1");
}

// Rewrites a database's journals as a binary from before the optimizers' own work was kept would
// have left them: without the own_work rows (kind 4), the others numbered without gaps.
void drop_own_work_from_journals(const std::string& path) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  char* error = nullptr;
  const int rc =
      sqlite3_exec(db,
                   "BEGIN; DELETE FROM replay WHERE kind=4; "
                   "CREATE TEMP TABLE renumbered AS SELECT run_id, (SELECT count(*) FROM replay b "
                   "WHERE b.run_id=a.run_id AND b.seq<a.seq) AS seq, kind, input_hash, payload FROM replay a; "
                   "DELETE FROM replay; INSERT INTO replay SELECT * FROM renumbered; COMMIT;",
                   nullptr, nullptr, &error);
  EXPECT_EQ(rc, SQLITE_OK) << (error ? error : "");
  sqlite3_free(error);
  sqlite3_close(db);
}

// "N results recalled, M computed again" of the resume summary: {N, M}, or {-1, -1}
std::pair<int, int> own_work_counts(const std::string& err) {
  int recalled = -1, again = -1;
  const auto at = err.find("own work (GP fits, acquisitions): ");
  if (at == std::string::npos ||
      std::sscanf(err.c_str() + at, "own work (GP fits, acquisitions): %d results recalled, %d computed again",
                  &recalled, &again) != 2)
    return {-1, -1};
  return {recalled, again};
}

TEST_F(HarnessCli, AGpOptimizerStoppedMidRunResumesWithoutRefittingAndEqualsTheUninterruptedRun) {
  // bo and boleap (leaps of 20 episodes, so that several GP fits come before the stop) stopped by
  // SIGTERM after episode 40 of 70: the resume recalls every GP fit and LCB argmin of the
  // interrupted attempt from the journal and computes none again, and the run's evals, best
  // point and diagnostics are the uninterrupted run's, bit for bit. The same journal without
  // those results (an older binary's) still resumes to the same bits, computing them again.
  for (const std::string opt : {"bo", "boleap"}) {
    const std::string grid = "--env rosenbrock-10 --optimizer " + opt +
        (opt == "boleap" ? " --set boleap.episodes_per_leap=20" : "") + " --seeds 1 --budget 70 --jobs 1 --quiet --db ";
    ASSERT_EQ(harness(grid + db(opt + "-full.sqlite")).code, 0) << opt;
    const auto stopped = harness(grid + db(opt + ".sqlite"),
                                 "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=40 DSB_FAULT_SIGNAL=15");
    EXPECT_EQ(stopped.code, 143) << opt << ": " << stopped.err;
    const std::string committed = scalar(db(opt + ".sqlite"), "SELECT episodes FROM runs WHERE status='running'");
    ASSERT_FALSE(committed.empty()) << opt;
    EXPECT_GE(std::stoi(committed), 40) << opt;  // boleap's batch ends its episode in progress
    EXPECT_LT(std::stoi(committed), 70) << opt;
    const int kept = std::stoi(scalar(db(opt + ".sqlite"), "SELECT count(*) FROM replay WHERE kind=4"));
    // bo: a fit after each of its first points and an argmin before each episode past the initial
    // design; boleap: a fit and an argmin per leap (episodes 11, 31: leaps of 20 after 11 Sobol points)
    EXPECT_GE(kept, opt == "bo" ? 40 : 4) << opt;
    // of which an older binary's resume computes again those before the journal's last episode
    // (the rest come after it, where the run goes on live)
    const int before_last = std::stoi(scalar(db(opt + ".sqlite"),
                                             "SELECT count(*) FROM replay WHERE kind=4 AND "
                                             "seq < (SELECT max(seq) FROM replay WHERE kind<>4)"));
    EXPECT_GT(before_last, 0) << opt;
    fs::copy_file(db(opt + ".sqlite"), db(opt + "-old.sqlite"));
    drop_own_work_from_journals(db(opt + "-old.sqlite"));
    EXPECT_EQ(scalar(db(opt + "-old.sqlite"), "SELECT count(*) FROM replay WHERE kind=4"), "0") << opt;

    const auto resumed = harness(grid + db(opt + ".sqlite"));
    ASSERT_EQ(resumed.code, 0) << opt << ": " << resumed.err;
    EXPECT_NE(resumed.err.find("resumed 1 interrupted runs, " + committed + " of their episodes replayed"),
              std::string::npos)
        << opt << ": " << resumed.err;
    EXPECT_EQ(own_work_counts(resumed.err), std::make_pair(kept, 0)) << opt << ": " << resumed.err;
    const auto old = harness(grid + db(opt + "-old.sqlite"));
    ASSERT_EQ(old.code, 0) << opt << ": " << old.err;
    EXPECT_EQ(own_work_counts(old.err), std::make_pair(0, before_last)) << opt << ": " << old.err;

    for (const std::string& resumed_db : {opt + ".sqlite", opt + "-old.sqlite"}) {
      expect_same_evals(read_evals(db(opt + "-full.sqlite")), read_evals(db(resumed_db)));
      for (const std::string column : {"status", "best_loss", "best_x", "diagnostics"})
        EXPECT_EQ(scalar(db(resumed_db), "SELECT " + column + " FROM runs"),
                  scalar(db(opt + "-full.sqlite"), "SELECT " + column + " FROM runs"))
            << resumed_db << ": " << column;
      EXPECT_EQ(scalar(db(resumed_db), "SELECT count(*) FROM replay"), "0") << resumed_db;
    }
  }
}

TEST_F(HarnessCli, SigkillMidRunLosesOnlyWhatWasNotCommitted) {
  // committing after every episode, a SIGKILL after episode 30 leaves exactly 30 to replay
  const std::string grid = "--env flip --optimizer gd --seeds 1 --budget 50 --jobs 1 --quiet --db ";
  ASSERT_EQ(harness(grid + db("full.sqlite")).code, 0);
  const auto killed = harness(grid + db("k.sqlite"),
                              "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=30 "
                              "DSB_FAULT_SIGNAL=9 DSB_FAULT_COMMIT_EVERY_EPISODE=1");
  EXPECT_EQ(killed.code, 128 + SIGKILL);
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT episodes FROM runs WHERE status='running'"), "30");
  const auto resumed = harness(grid + db("k.sqlite"));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("resumed 1 interrupted runs, 30 of their episodes replayed"), std::string::npos)
      << resumed.err;
  expect_same_evals(read_evals(db("full.sqlite")), read_evals(db("k.sqlite")));
}

TEST_F(HarnessCli, ASecondHarnessOnTheSameDatabaseIsRefusedAndSigtermStopsTheFirst) {
  const std::string grid = "--env cartpole3 --optimizer cmaes --seeds 2 --budget 20000 --jobs 1 --quiet";
  const pid_t pid = testing::start_harness(grid + " --db " + db("l.sqlite"));
  ASSERT_GE(pid, 0);
  const bool started = wait_until(db("l.sqlite"), "SELECT count(*) FROM runs WHERE status='running'", "1", pid,
                                  std::chrono::seconds(120));
  const auto second = started ? harness(grid + " --db " + db("l.sqlite")) : Result{};
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(started) << "no run row 'running' appeared";
  EXPECT_EQ(second.code, 2) << second.err;
  EXPECT_EQ(std::count(second.err.begin(), second.err.end(), '\n'), 1) << second.err;
  EXPECT_NE(second.err.find("is in use by another harness (pid " + std::to_string(pid)), std::string::npos)
      << second.err;
  // SIGTERM from outside: the first harness commits and exits 143
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 143);
  EXPECT_EQ(scalar(db("l.sqlite"), "SELECT count(*) FROM runs WHERE status='running'"), "1");
}

TEST_F(HarnessCli, EvalsAreBitIdenticalWhateverTheNumberOfThreads) {
  // threads inside each run: cmaes, boleap and random evaluate their batches over the team, and
  // rastrigin-9000 reduces over blocks of coordinates on it (gd: one rollout at a time, threaded).
  // --threads is capped at the usable CPUs (2 in CI); odd team sizes are covered below the CLI
  // (test_budget's RunsAreBitIdenticalForAnyTeamSize, test_parallel)
  const std::string batches = "--env cartpole1 --optimizer random,cmaes,boleap --seeds 1 --budget 40 --quiet";
  const std::string inside = "--env rastrigin-9000 --optimizer gd,random --seeds 1 --budget 20 --quiet";
  for (const auto& [name, threads] : std::vector<std::pair<std::string, std::string>>{
           {"t1", "--jobs 1 --threads 1"}, {"t2", "--jobs 1 --threads 2"}, {"t3", "--jobs 2 --threads 2"}}) {
    ASSERT_EQ(harness(batches + " " + threads + " --db " + db(name + ".sqlite")).code, 0);
    ASSERT_EQ(harness(inside + " " + threads + " --db " + db(name + ".sqlite")).code, 0);
  }
  const auto a = read_evals(db("t1.sqlite"));
  EXPECT_EQ(a.size(), 3u * 40u + 2u * 20u);
  expect_same_evals(a, read_evals(db("t2.sqlite")));
  expect_same_evals(a, read_evals(db("t3.sqlite")));
}

TEST_F(HarnessCli, PlanCountsTheGridAndWritesNothing) {
  const auto r = harness("plan --all --seeds 5 --db " + db("plan.sqlite"));
  ASSERT_EQ(r.code, 0) << r.err;
  GridRequest all;
  all.all = true;
  all.seeds = 5;
  const std::size_t runs = expand_grid(all).size();  // 13 envs x 10 optimizers x 5 seeds today
  EXPECT_GE(runs, 650u);
  EXPECT_NE(r.out.find("plan: " + std::to_string(runs) + " runs in the grid; 0 already done"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("env models built: 0"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(db("plan.sqlite")));
  // runs already done are counted as such
  ASSERT_EQ(
      harness("--env sphere-2,branin --optimizer random --seeds 3 --budget 5 --quiet --db " + db("p.sqlite")).code, 0);
  const std::string before = read(db("p.sqlite"));
  const auto p =
      harness("plan --env sphere-2,branin,bounce --optimizer random --seeds 3 --budget 5 --db " + db("p.sqlite"));
  EXPECT_NE(p.out.find("9 runs in the grid; 6 already done"), std::string::npos) << p.out;
  EXPECT_NE(p.out.find("3 to run (15 episodes)"), std::string::npos) << p.out;
  EXPECT_EQ(read(db("p.sqlite")), before);
}

TEST_F(HarnessCli, BadInputExitsTwoWithOneLineNamingTheValueAndKeepsTheDatabase) {
  ASSERT_EQ(harness("--env sphere-2 --optimizer random --seeds 1 --budget 5 --quiet --db " + db("keep.sqlite")).code,
            0);
  const std::string before = read(db("keep.sqlite"));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--env nosuchenv --optimizer random --seeds 1", "nosuchenv"},
      {"--env sphere-2 --optimizer nosuchopt --seeds 1", "nosuchopt"},
      {"--env sphere-0 --optimizer random", "sphere-0"},
      {"--env sphere-2 --optimizer random --seeds abc", "abc"},
      {"--env sphere-2 --optimizer random --budget 1e", "1e"},
      {"--env sphere-2 --optimizer random --seeds 0", "0"},
      {"--env sphere-2 --optimizer random --jobs -3", "-3"},
      {"--env sphere-2 --optimizer random --threads 0", "0"},
      {"--env sphere-2 --optimizer random --shard 3/2", "3/2"},
      {"--env sphere-2 --optimizer random --budget 99999999999999999999", "99999999999999999999"},
      {"--env sphere-2 --optimizer random --budget 1000001", "1000001"},
      {"--all --bogus-flag", "--bogus-flag"},
      {"--env sphere-2 --optimizer boleap --set boleap.sigma0", "boleap.sigma0"},
      {"--env sphere-2 --optimizer boleap --set boleap.nosuchknob=1", "nosuchknob"},
      {"--env sphere-2 --optimizer boleap --set boleap.sigma0=-0.5", "sigma0"},
      {"--env sphere-2 --optimizer boleap --set boleap.patience=2.5", "2.5"},
      {"--env sphere-2 --optimizer boleap --set cmaes.sigma0=0.3", "cmaes"},
      {"--env sphere-2 --optimizer random --set random.x=1", "random"},
  };
  for (const auto& [args, bad] : cases) {
    const auto r = harness(args + " --db " + db("keep.sqlite"));
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(read(db("keep.sqlite")), before) << args;
  }
  // a kernel path forced from the environment that does not exist: refused before any run
  for (const auto& [prefix, bad] : std::vector<std::pair<std::string, std::string>>{
           {"DSB_SIMD=avx512", "avx512"}, {"DSB_SIMD=neon", "neon"}, {"DSB_MPM_LANES=scalar", "DSB_MPM_LANES"}}) {
    const auto r = harness("--env sphere-2 --optimizer random --seeds 1 --db " + db("keep.sqlite"), prefix);
    EXPECT_EQ(r.code, 2) << prefix;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << prefix << ": " << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << prefix << ": " << r.err;
    EXPECT_EQ(read(db("keep.sqlite")), before) << prefix;
  }
  // eval: wrong dimension, a non-number, outside the box, unknown env, a variant of bounce (which has none)
  const std::vector<std::pair<std::string, std::string>> eval_cases = {
      {"eval --env sphere-3 --x 0.1,0.2", "3"},    {"eval --env sphere-2 --x 0.1,abc", "abc"},
      {"eval --env sphere-2 --x 0.1,1.5", "1.5"},  {"eval --env nosuch --x 0.1", "nosuch"},
      {"eval --env bounce-2 --x 0.1", "bounce-2"},
  };
  for (const auto& [args, bad] : eval_cases) {
    const auto r = harness(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << args << ": " << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  // --db '' (SQLite would open a temporary database and keep nothing)
  {
    const auto r = harness("--env sphere-2 --optimizer random --db ''");
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--db must name a file, got ''"), std::string::npos) << r.err;
  }
  // a SQLite file of somebody else's without any table: refused, not stamped
  {
    const std::string other = db("other.sqlite");
    sqlite3* h = nullptr;
    ASSERT_EQ(sqlite3_open(other.c_str(), &h), SQLITE_OK);
    sqlite3_exec(h, "PRAGMA user_version=7; CREATE TABLE t(x); DROP TABLE t;", nullptr, nullptr, nullptr);
    sqlite3_close(h);
    const std::string bytes = read(other);
    ASSERT_FALSE(bytes.empty());
    const auto r = harness("--env sphere-2 --optimizer random --db " + other);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("without harness tables"), std::string::npos) << r.err;
    EXPECT_EQ(read(other), bytes);
  }
  // unwritable database paths
  for (const std::string& path : {db("no/such/dir/r.sqlite"), dir_.string()}) {
    const auto r = harness("--env sphere-2 --optimizer random --db " + path);
    EXPECT_EQ(r.code, 2) << path;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(path), std::string::npos) << r.err;
  }
}

TEST_F(HarnessCli, KnobVariantsAreSeparateRunsWithTheirOwnConfigs) {
  // a knob left at its default is the default run (same config hash, nothing to do); another
  // value is another run, stored with its resolved config, with different evals
  const std::string base =
      "--env sphere-10 --optimizer rand-descents --seeds 1 --budget 50 --quiet --db " + db("k.sqlite");
  ASSERT_EQ(harness(base).code, 0);
  const auto r = harness(base + " --set rand-descents.start_scale=1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT COUNT(*) FROM runs"), "1");
  ASSERT_EQ(harness(base + " --set rand-descents.start_scale=0.1 --set rand-descents.max_steps=7").code, 0);
  EXPECT_EQ(scalar(db("k.sqlite"), "SELECT COUNT(*) FROM runs WHERE status='done'"), "2");
  const auto cfg = nlohmann::json::parse(scalar(
      db("k.sqlite"), "SELECT c.json FROM runs r JOIN configs c ON c.hash = r.opt_config_hash ORDER BY r.run_id DESC"));
  EXPECT_EQ(cfg["start_scale"].get<double>(), 0.1);
  EXPECT_EQ(cfg["max_steps"].get<int>(), 7);
  EXPECT_NE(scalar(db("k.sqlite"), "SELECT loss FROM evals WHERE run_id=1 AND episode=0"),
            scalar(db("k.sqlite"), "SELECT loss FROM evals WHERE run_id=2 AND episode=0"));
  // a Slurm array runs the same variant
  const auto slurm = harness(
      "slurm --env sphere-10 --optimizer rand-descents --seeds 2 --budget 50 --set "
      "rand-descents.max_steps=7 --shards 2 --dir " +
      db("slurm"));
  ASSERT_EQ(slurm.code, 0) << slurm.err;
  EXPECT_NE(read(dir_ / "slurm" / "array.sbatch").find("--set rand-descents.max_steps=7 --shard"), std::string::npos);
}

TEST_F(HarnessCli, EvalPrintsTheLossAndGradientAsJson) {
  const auto env = make_env("cartpole1");
  std::vector<double> x(env->dim(), 0.0);
  x[0] = 0.5;
  x[1] = -0.25;
  std::string xs;
  for (std::size_t i = 0; i < x.size(); ++i) xs.append(i ? "," : "").append(std::to_string(x[i]));
  const auto r = harness("eval --env cartpole1 --grad --x " + xs);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["env"], "cartpole1");
  EXPECT_EQ(j["loss"].get<double>(), env->loss(x));
  std::vector<double> grad(env->dim());
  env->loss_and_grad(x, grad);
  ASSERT_EQ(j["grad"].size(), grad.size());
  for (std::size_t i = 0; i < grad.size(); ++i) EXPECT_EQ(j["grad"][i].get<double>(), grad[i]);
}

TEST_F(HarnessCli, ListGradcheckVersionAndHelp) {
  const auto list = harness("list");
  ASSERT_EQ(list.code, 0);
  EXPECT_NE(list.out.find("cartpole3"), std::string::npos);
  EXPECT_NE(list.out.find("400"), std::string::npos);
  EXPECT_NE(list.out.find("cmaes"), std::string::npos);
  EXPECT_NE(list.out.find("ext:NAME"), std::string::npos) << list.out;
  // every optimizer with knobs lists exactly the keys --set accepts
  const auto knobs_at = list.out.find("knobs (--set");
  ASSERT_NE(knobs_at, std::string::npos) << list.out;
  for (const auto& e : optimizer_entries()) {
    if (e.knobs.empty()) continue;
    std::string line = fmt::format("{:<22} {}", e.name, fmt::join(e.knobs, ", "));
    EXPECT_NE(list.out.find(line + "\n", knobs_at), std::string::npos) << line;
  }
  const auto gc = harness("gradcheck --env cartpole3 --points 2 --seed 1 --amplitude 0.3");
  EXPECT_EQ(gc.code, 0) << gc.out;
  EXPECT_NE(gc.out.find("PASS"), std::string::npos);
  const auto version = harness("--version");
  EXPECT_EQ(version.code, 0);
  EXPECT_NE(version.out.find("harness 0."), std::string::npos) << version.out;
  // the commit it was built from, refreshed at every build (cmake/git_sha.cmake): the checkout's
  // HEAD, "-dirty" after it when tracked files differed; "unknown" outside a git checkout
  std::string head;
  if (FILE* git = popen("git -C '" DSB_SOURCE_DIR "' rev-parse --short=12 HEAD 2>/dev/null", "r")) {
    char buf[64] = {};
    if (std::fgets(buf, sizeof buf, git)) head = buf;
    pclose(git);
  }
  while (!head.empty() && (head.back() == '\n' || head.back() == ' ')) head.pop_back();
  EXPECT_NE(version.out.find("(git " + (head.empty() ? std::string("unknown") : head)), std::string::npos)
      << version.out << " against HEAD " << head;
  EXPECT_EQ(harness("--help").code, 0);
  EXPECT_EQ(harness("eval --help").code, 0);
}

// a `harness landscape` CSV: its header line and every row's numbers
struct LandscapeCsv {
  std::string header;
  std::vector<std::vector<double>> rows;
};
LandscapeCsv read_landscape(const std::string& path) {
  LandscapeCsv csv;
  std::ifstream in(path);
  std::getline(in, csv.header);
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    auto& v = csv.rows.emplace_back();
    for (std::string f; std::getline(s, f, ',');) v.push_back(std::stod(f));
  }
  return csv;
}

TEST_F(HarnessCli, LandscapeWritesTheGridWithLossAndGradient) {
  const std::string out = db("land.csv");
  const auto r = harness("landscape --env branin --dims 0,1 --res 7 --out " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  const LandscapeCsv csv = read_landscape(out);
  EXPECT_EQ(csv.header, "i,j,xi,xj,loss,grad_i,grad_j");
  const auto env = make_env("branin");
  ASSERT_EQ(csv.rows.size(), 49u);
  for (const auto& v : csv.rows) {
    ASSERT_EQ(v.size(), 7u);
    const std::vector<double> x{v[2], v[3]};
    std::vector<double> g(2);
    EXPECT_EQ(v[4], env->loss_and_grad(x, g)) << v[2] << ", " << v[3];  // 17 digits round-trip exactly
    EXPECT_EQ(v[5], g[0]);
    EXPECT_EQ(v[6], g[1]);
  }
  // bad slices: one line naming the value, exit 2
  for (const std::string& bad : {std::string("--dims 0,0"), std::string("--dims 0,2"), std::string("--dims a,1")}) {
    const auto b = harness("landscape --env branin " + bad + " --res 5 --out " + out);
    EXPECT_EQ(b.code, 2) << bad;
    EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
  }
  EXPECT_EQ(harness("landscape --env branin --dims 0,1 --res 1 --out " + out).code, 2);
  EXPECT_EQ(harness("landscape --env branin --dims 0,1 --res 5 --center 0.1 --out " + out).code, 2);
}

TEST_F(HarnessCli, LandscapeChecksTheGradientAtEveryPoint) {
  const std::string out = db("land_check.csv");
  const auto r = harness("landscape --env branin --dims 0,1 --res 6 --check-step 1e-6 --out " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("agrees with central differences (step 1e-06, tolerance 0.0001) at 36 of 36 points"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("within 25 degrees of the differences' at 36 (100.0%) and opposed (cos < 0) at 0 (0.0%) of 36"),
            std::string::npos)
      << r.err;
  const LandscapeCsv csv = read_landscape(out);
  EXPECT_EQ(csv.header, "i,j,xi,xj,loss,grad_i,grad_j,fd_i,fd_j,rel_err,agrees");
  const auto env = make_env("branin");
  ASSERT_EQ(csv.rows.size(), 36u);
  for (const auto& v : csv.rows) {
    ASSERT_EQ(v.size(), 11u);
    const std::vector<double> x{v[2], v[3]};
    std::vector<double> g(2);
    EXPECT_EQ(v[4], env->loss_and_grad(x, g)) << v[2] << ", " << v[3];
    EXPECT_EQ(v[5], g[0]);
    EXPECT_EQ(v[6], g[1]);
    // the differences are the checker's own, and agree with branin's exact gradient
    const auto fi = finite_differences(*env, x, 0, 1e-6);
    const auto fj = finite_differences(*env, x, 1, 1e-6);
    EXPECT_EQ(v[7], fi.central);
    EXPECT_EQ(v[8], fj.central);
    EXPECT_LE(v[9], 1e-4) << v[2] << ", " << v[3];
    EXPECT_EQ(v[10], 1.0);
  }
  // a tolerance below what central differences reach: some points no longer agree, and say so
  const auto tight =
      harness("landscape --env branin --dims 0,1 --res 6 --check-step 1e-6 --tol 1e-12 --force --out " + out);
  ASSERT_EQ(tight.code, 0) << tight.err;
  EXPECT_EQ(tight.err.find("at 36 of 36"), std::string::npos) << tight.err;
  // bad check options: one line naming the value, exit 2
  for (const std::string& bad :
       {std::string("--check-step 0"), std::string("--check-step 0.5"), std::string("--check-step 1e-6 --tol -1")}) {
    const auto b = harness("landscape --env branin --dims 0,1 --res 3 " + bad + " --out " + out);
    EXPECT_EQ(b.code, 2) << bad;
    EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
  }
}

TEST_F(HarnessCli, ShardsPartitionTheGrid) {
  const std::string grid = "--env sphere-2,branin --optimizer random,cmaes --seeds 3 --budget 5 --quiet";
  ASSERT_EQ(harness(grid + " --db " + db("all.sqlite")).code, 0);
  for (int i = 0; i < 3; ++i)
    ASSERT_EQ(harness(grid + " --shard " + std::to_string(i) + "/3 --db " + db("s.sqlite")).code, 0);
  EXPECT_EQ(scalar(db("s.sqlite"), "SELECT count(*) FROM runs"), "12");
  expect_same_evals(read_evals(db("all.sqlite")), read_evals(db("s.sqlite")));
}

TEST_F(HarnessCli, ShardsAreCutFromRunKeysSoAddingAnEnvMovesNoRun) {
  // shard 0 of 3 of a grid, and of the same grid with one more env and the names reordered
  const std::string runs_sql =
      "SELECT group_concat(env || '/' || optimizer || '/' || seed, ' ') FROM "
      "(SELECT env, optimizer, seed FROM runs WHERE env != 'hartmann6' ORDER BY 1, 2, 3)";
  ASSERT_EQ(harness("--env sphere-2,branin --optimizer random,cmaes --seeds 3 --budget 5 --quiet --shard 0/3 --db " +
                    db("a.sqlite"))
                .code,
            0);
  ASSERT_EQ(harness("--env hartmann6,branin,sphere-2 --optimizer cmaes,random --seeds 3 --budget 5 --quiet "
                    "--shard 0/3 --db " +
                    db("b.sqlite"))
                .code,
            0);
  const std::string a = scalar(db("a.sqlite"), runs_sql);
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, scalar(db("b.sqlite"), runs_sql));
}

TEST_F(HarnessCli, CalibrateCachesEpisodeCostsThatPlanAndTheRunOrderUse) {
  const std::string cache = "DSB_COST_CACHE=" + db("costs.json") + " ";
  const std::string grid = "--env cartpole1,sphere-2 --optimizer random --seeds 1 --budget 5";
  const auto before = harness("plan " + grid + " --db " + db("p.sqlite"), cache);
  EXPECT_NE(before.out.find("measured on this machine for 0 of 2 envs"), std::string::npos) << before.out;
  EXPECT_NE(before.out.find("`harness calibrate " + grid + "` measures them"), std::string::npos) << before.out;
  const auto c = harness("calibrate " + grid, cache);
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("measured now"), std::string::npos) << c.out;
  const auto j = nlohmann::json::parse(read(db("costs.json")));
  EXPECT_EQ(j.at("costs").size(), 2u);
  for (const auto& [key, v] : j.at("costs").items()) {
    EXPECT_GT(v.at("forward_s").get<double>(), 0.0) << key;
    EXPECT_GT(v.at("gradient_s").get<double>(), 0.0) << key;
  }
  const auto again = harness("calibrate " + grid, cache);
  EXPECT_EQ(again.out.find("measured now"), std::string::npos) << again.out;  // cached
  const auto after = harness("plan " + grid + " --db " + db("p.sqlite"), cache);
  EXPECT_NE(after.out.find("measured on this machine for 2 of 2 envs"), std::string::npos) << after.out;
  // the run starts the cheaper env first (sphere-2, though named second)
  ASSERT_EQ(harness(grid + " --jobs 1 --quiet --db " + db("r.sqlite"), cache).code, 0);
  EXPECT_EQ(scalar(db("r.sqlite"), "SELECT env FROM runs ORDER BY run_id LIMIT 1"), "sphere-2");
}

TEST_F(HarnessCli, ReportOptionWritesTheReportWhenTheGridEnds) {
  const auto r = harness("--env sphere-2,branin --optimizer random,cmaes --seeds 2 --budget 10 --quiet --db " +
                         db("r.sqlite") + " --report " + db("rep"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("report written to " + db("rep")), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "rep" / "index.html"));
}

TEST_F(HarnessCli, ACtrlCDuringTheReportBuildLetsTheReportFinish) {
  // A stand-in generator (DSB_PYTHON=/bin/sh runs DSB_REPORTS_DIR/make_report.py) does what a
  // terminal's Ctrl-C does while the end-of-grid report is being written: SIGINT to the whole
  // foreground process group (setsid gives the harness a group of its own). The generator must
  // live on and finish; the harness stops in order (exit 130) and says the report was written.
  fs::create_directories(dir_ / "gen");
  std::ofstream(dir_ / "gen" / "make_report.py") << "kill -INT 0\necho finished > " << path("gen/finished") << "\n";
  const auto r = harness("--env sphere-2 --optimizer random --seeds 1 --budget 5 --quiet --db " + db("r.sqlite") +
                             " --report " + db("rep"),
                         "DSB_PYTHON=/bin/sh DSB_REPORTS_DIR=" + path("gen") + " setsid --wait");
  EXPECT_EQ(r.code, 128 + SIGINT) << r.err;
  EXPECT_NE(r.err.find("report written to " + db("rep")), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("FAILED"), std::string::npos) << r.err;
  EXPECT_EQ(read(dir_ / "gen" / "finished"), "finished\n");
  EXPECT_EQ(scalar(db("r.sqlite"), "SELECT count(*) FROM runs WHERE status='done'"), "1");
}

TEST_F(HarnessCli, MergeCombinesShardsAndRefusesConflicts) {
  const std::string grid = "--env sphere-2,branin,cartpole1 --optimizer random,cmaes,gd --seeds 2 --budget 8 --quiet";
  ASSERT_EQ(harness(grid + " --db " + db("all.sqlite")).code, 0);
  std::string shards;
  for (int i = 0; i < 4; ++i) {
    const std::string f = db("shard-" + std::to_string(i) + ".sqlite");
    ASSERT_EQ(harness(grid + " --shard " + std::to_string(i) + "/4 --db " + f).code, 0);
    shards += " " + f;
  }
  // a shard given twice is an identical duplicate
  const auto m = harness("merge --into " + db("merged.sqlite") + shards + " " + db("shard-0.sqlite"));
  ASSERT_EQ(m.code, 0) << m.err;
  EXPECT_NE(m.err.find("18 runs added"), std::string::npos) << m.err;
  expect_same_evals(read_evals(db("all.sqlite")), read_evals(db("merged.sqlite")));
  ASSERT_EQ(harness("export --db " + db("all.sqlite") + " --out " + db("all.csv")).code, 0);
  ASSERT_EQ(harness("export --db " + db("merged.sqlite") + " --out " + db("merged.csv")).code, 0);
  EXPECT_EQ(read(db("all.csv")), read(db("merged.csv")));

  // the same run with one different loss: refused, naming the run, nothing written
  const std::string bad = db("shard-1.sqlite");
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(bad.c_str(), &h), SQLITE_OK);
  ASSERT_EQ(
      sqlite3_exec(h, "UPDATE evals SET loss = loss * 2 WHERE episode = 3 AND run_id = (SELECT min(run_id) FROM runs)",
                   nullptr, nullptr, nullptr),
      SQLITE_OK);
  sqlite3_close(h);
  const std::string before = read(db("merged.sqlite"));
  const auto c = harness("merge --into " + db("merged.sqlite") + " " + bad);
  EXPECT_EQ(c.code, 2);
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
  EXPECT_NE(c.err.find("conflicts with its copy from"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("/seed "), std::string::npos) << c.err;
  EXPECT_EQ(read(db("merged.sqlite")), before);

  // a run still 'running' in a shard never replaces a done one, and a foreign input is refused
  // before the output is touched
  const auto r = harness("merge --into " + db("merged.sqlite") + " " + db("nosuch.sqlite"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nosuch.sqlite"), std::string::npos) << r.err;
  ASSERT_EQ(sqlite3_open(bad.c_str(), &h), SQLITE_OK);
  ASSERT_EQ(
      sqlite3_exec(h, "UPDATE evals SET loss = loss / 2 WHERE episode = 3 AND run_id = (SELECT min(run_id) FROM runs)",
                   nullptr, nullptr, nullptr),
      SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(h, "UPDATE runs SET status='running'", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(h);
  const auto k = harness("merge --into " + db("merged.sqlite") + " " + bad);
  ASSERT_EQ(k.code, 0) << k.err;
  expect_same_evals(read_evals(db("all.sqlite")), read_evals(db("merged.sqlite")));
  EXPECT_NE(k.err.find("0 runs added"), std::string::npos) << k.err;
}

}  // namespace
}  // namespace dsb
