// External optimizers over the JSON-lines protocol (docs/ext-protocol.md): the protocol against
// a plain objective (probe, exact numbers, batches past the budget, early stop, gradients where
// there are none), and the `harness` program end to end: the scipy and Optuna examples next to
// built-in optimizers give the same database on rerun and for any --jobs; every failure mode (crash,
// garbage, a point outside the box, a hang past the timeout, asking after the end) fails only its
// own run, with a reason naming the optimizer, and leaves the other runs and the database as
// they were; the version is in the run key; SIGTERM mid-run resumes by replay; slurm carries --ext.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <tuple>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "optimizers/ext/ext_optimizer.hpp"
#include "support/function_objective.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

const std::string kPython = "/usr/bin/python3";
const std::string kSource = DSB_SOURCE_DIR;

// the command of tests/ext/test_optimizer.py in MODE
std::string test_optimizer(const std::string& mode, int batch = 1) {
  return kPython + " " + kSource + "/tests/ext/test_optimizer.py " + mode + " " + std::to_string(batch);
}

ExtOptimizerSpec probed(const std::string& name, const std::string& command, double timeout_s = 10.0) {
  return ext_probe({name, command, timeout_s, "", ""});
}

// what minimize() threw, "" when it returned or the budget ended
std::string run_error(Optimizer& opt, Objective& f) {
  Rng rng(1);
  try {
    opt.minimize(f, rng);
  } catch (const BudgetExhausted&) {
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

double sphere(std::span<const double> x) {
  double s = 0.0;
  for (double v : x) s += (v - 0.25) * (v - 0.25);
  return s;
}

TEST(ExtProtocol, TheProbeLearnsNameAndVersionAndRefusesABrokenProgram) {
  const auto spec = probed("r", test_optimizer("random"));
  EXPECT_EQ(spec.reported_name, "test-random");
  EXPECT_EQ(spec.version, "1");
  const auto opt = make_ext_optimizer(spec, "sphere-3", 7);
  EXPECT_EQ(opt->name(), "ext:r");
  EXPECT_EQ(opt->config(),
            nlohmann::json(
                {{"protocol", 1}, {"command", test_optimizer("random")}, {"name", "test-random"}, {"version", "1"}}));
  try {
    probed("bad", test_optimizer("bad-probe"));
    FAIL() << "the probe accepted a program that exits before its hello";
  } catch (const UsageError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("ext:bad: probe of '" + test_optimizer("bad-probe") + "' failed: ", 0), 0u) << m;
    EXPECT_NE(m.find("exited with status 4"), std::string::npos) << m;
    EXPECT_NE(m.find("stderr: cannot start: missing module"), std::string::npos) << m;
  }
  EXPECT_THROW(probed("none", "/nonexistent/program"), UsageError);
  EXPECT_THROW(probed("quiet", "cat > /dev/null", 0.5), UsageError);  // never says hello: timeout
}

TEST(ExtProtocol, NumbersCrossThePipesBitForBitAsJsonTextAndAsBase64) {
  // the program sends each loss and gradient component back as the next point's x[0], x[1]
  for (const std::string mode : {"roundtrip", "roundtrip-binary"}) {
    auto f = [](std::span<const double> x) { return std::sin(1000.0 * x[0] + 7.0 * x[1]); };
    auto g = [&](std::span<const double> x, std::span<double> grad) {
      std::fill(grad.begin(), grad.end(), 0.0);
      grad[1] = 0.999 * std::cos(1000.0 * x[0] + 7.0 * x[1]);
      return f(x);
    };
    testing::FunctionObjective obj(3, 40, f, g);
    auto opt = make_ext_optimizer(probed("rt", test_optimizer(mode)), "rt", 1);
    EXPECT_EQ(run_error(*opt, obj), "") << mode;
    ASSERT_EQ(obj.points().size(), 40u) << mode;
    for (std::size_t k = 1; k < 40; ++k) {
      const auto& prev = obj.points()[k - 1];
      const double loss = obj.losses()[k - 1], grad1 = 0.999 * std::cos(1000.0 * prev[0] + 7.0 * prev[1]);
      EXPECT_EQ(std::memcmp(&obj.points()[k][0], &loss, sizeof loss), 0) << mode << " " << k;
      EXPECT_EQ(std::memcmp(&obj.points()[k][1], &grad1, sizeof grad1), 0) << mode << " " << k;
    }
    EXPECT_EQ(opt->diagnostics()["end"], "budget");
    EXPECT_EQ(opt->diagnostics()["grad_asks"], 40);
  }
}

TEST(ExtProtocol, BatchesStopAtTheBudgetAndAnEarlyStopEndsTheRun) {
  testing::FunctionObjective batch(4, 20, sphere);
  auto opt = make_ext_optimizer(probed("b", test_optimizer("random", 7)), "s", 3);
  EXPECT_EQ(run_error(*opt, batch), "");
  EXPECT_EQ(batch.used(), 20);  // 7 + 7 + 6 of the last ask's 7
  EXPECT_EQ(opt->diagnostics()["asks"], 3);
  EXPECT_EQ(opt->diagnostics()["points"], 20);
  EXPECT_EQ(opt->diagnostics()["largest_ask"], 7);

  testing::FunctionObjective early(4, 50, sphere);
  auto stopper = make_ext_optimizer(probed("e", test_optimizer("stop-early")), "s", 3);
  EXPECT_EQ(run_error(*stopper, early), "");
  EXPECT_EQ(early.used(), 10);
  EXPECT_EQ(stopper->diagnostics()["end"], "optimizer");
}

TEST(ExtProtocol, EachBreachFailsWithOneLineNamingTheOptimizerAndTheReason) {
  const std::map<std::string, std::string> want = {
      {"crash", "ext:crash: closed its stdout and exited with status 3 before the budget end; stderr: Traceback"},
      {"garbage", "ext:garbage: malformed line 'this is not json' (not a JSON object)"},
      {"outside", "ext:outside: point 0 of the ask has x[1] = 1.5, outside the box [-1, 1]"},
      {"hang", "ext:hang: no reply within the timeout of 1.0 s (waiting for an ask)"},
      {"after-end", "ext:after-end: asked for points after the budget end"},
      {"grad", "ext:grad: asked for gradients, but env 'plain' has none (the hello said gradient: false)"},
      {"bad-base64", "ext:bad-base64: malformed ask (the base64 string does not decode to doubles)"},
  };
  for (const auto& [mode, message] : want) {
    testing::FunctionObjective f(3, 8, sphere);  // no gradient
    auto opt = make_ext_optimizer(probed(mode, test_optimizer(mode), 1.0), "plain", 5);
    const std::string error = run_error(*opt, f);
    EXPECT_EQ(error.rfind(message, 0), 0u) << mode << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
    EXPECT_EQ(f.used(), mode == "after-end" ? 8 : 3) << mode;
  }
}

// ---- the harness program ----

class ExtCli : public dsb::testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args, const std::string& env_prefix = "") {
    return testing::run_harness(dir_, args, env_prefix);
  }
  std::string db(const std::string& name) const { return path(name); }
};

using testing::rows;
using testing::scalar;

// every episode of every run (key, episode, loss, best, grad, failed), without timings
std::vector<std::string> evals_of(const std::string& path, const std::string& where = "1") {
  return rows(path,
              "SELECT r.env, r.optimizer, r.seed, r.status, r.opt_config_hash, e.episode, e.loss, e.best_loss, "
              "e.used_grad, e.failed FROM evals e JOIN runs r USING(run_id) WHERE " +
                  where + " ORDER BY r.env, r.optimizer, r.seed, e.episode");
}

const std::string kExamples = "--ext lbfgsb='" + kPython + " " + kSource + "/examples/ext/scipy_lbfgsb.py' --ext de='" +
    kPython + " " + kSource + "/examples/ext/scipy_de.py'";
const std::string kExampleGrid =
    "--env sphere-10,cartpole1 --optimizer ext:lbfgsb,ext:de,cmaes,gd --seeds 2 "
    "--budget 60 --quiet " +
    kExamples;

TEST_F(ExtCli, ScipyExamplesBesideBuiltInsGiveTheSameDatabaseOnRerunAndForAnyJobs) {
  const auto first = harness(kExampleGrid + " --jobs 1 --db " + db("a.sqlite"));
  ASSERT_EQ(first.code, 0) << first.err;
  EXPECT_EQ(scalar(db("a.sqlite"), "SELECT count(*) FROM runs WHERE status='done' AND episodes=60"), "16");
  EXPECT_EQ(scalar(db("a.sqlite"), "SELECT count(*) FROM evals"), "960");
  ASSERT_EQ(harness(kExampleGrid + " --jobs 1 --db " + db("b.sqlite")).code, 0);
  ASSERT_EQ(harness(kExampleGrid + " --jobs 2 --threads 1 --db " + db("c.sqlite")).code, 0);
  const auto a = evals_of(db("a.sqlite"));
  EXPECT_EQ(a, evals_of(db("b.sqlite")));
  EXPECT_EQ(a, evals_of(db("c.sqlite")));
  // L-BFGS-B asked with gradients on both envs, DE in batches
  EXPECT_EQ(scalar(db("a.sqlite"),
                   "SELECT min(e.used_grad) FROM evals e JOIN runs r USING(run_id) "
                   "WHERE r.optimizer='ext:lbfgsb'"),
            "1");
  EXPECT_EQ(scalar(db("a.sqlite"),
                   "SELECT max(json_extract(diagnostics, '$.optimizer.largest_ask')) FROM runs "
                   "WHERE optimizer='ext:de'"),
            "5");
  // the config holds the command and the version the program reported
  const std::string config = scalar(db("a.sqlite"),
                                    "SELECT c.json FROM configs c JOIN runs r ON "
                                    "c.hash=r.opt_config_hash WHERE r.optimizer='ext:lbfgsb' LIMIT 1");
  EXPECT_NE(config.find("examples/ext/scipy_lbfgsb.py"), std::string::npos) << config;
  EXPECT_NE(config.find("\"version\":\"1 (scipy "), std::string::npos) << config;
  // the medians beside the built-ins (docs/optimizers.md "Benchmark your own optimizer")
  for (const auto& r : rows(db("a.sqlite"),
                            "SELECT env, optimizer, group_concat(best_loss, ' ') FROM "
                            "(SELECT * FROM runs ORDER BY best_loss) GROUP BY env, optimizer"))
    std::cout << "final best (2 seeds, 60 episodes): " << r << "\n";
}

TEST_F(ExtCli, OptunaTpeBesideBuiltInsGivesTheSameDatabaseForAnyJobs) {
  const std::string grid =
      "--env sphere-10,bounce --optimizer ext:tpe,cmaes,random --seeds 2 --budget 40 --quiet "
      "--ext tpe='" +
      kPython + " " + kSource + "/examples/ext/optuna_tpe.py' --db ";
  const auto first = harness(grid + db("a.sqlite") + " --jobs 1");
  ASSERT_EQ(first.code, 0) << first.err;
  EXPECT_EQ(scalar(db("a.sqlite"), "SELECT count(*) FROM runs WHERE status='done' AND episodes=40"), "12");
  ASSERT_EQ(harness(grid + db("b.sqlite") + " --jobs 2").code, 0);
  EXPECT_EQ(evals_of(db("a.sqlite")), evals_of(db("b.sqlite")));
  for (const auto& r : rows(db("a.sqlite"),
                            "SELECT env, optimizer, group_concat(best_loss, ' ') FROM "
                            "(SELECT * FROM runs ORDER BY best_loss) GROUP BY env, optimizer"))
    std::cout << "final best (2 seeds, 40 episodes): " << r << "\n";
}

TEST_F(ExtCli, EachFailureModeFailsOnlyItsRunAndLeavesTheDatabaseIntact) {
  // a database with an earlier grid in it
  ASSERT_EQ(harness("--env branin --optimizer cmaes --seeds 1 --budget 15 --quiet --db " + db("f.sqlite")).code, 0);
  const auto before = evals_of(db("f.sqlite"));
  ASSERT_EQ(harness("--env sphere-10 --optimizer random --seeds 1 --budget 20 --quiet --db " + db("ref.sqlite")).code,
            0);

  std::string ext = "--optimizer random";
  for (const std::string mode : {"crash", "garbage", "outside", "hang", "after-end"}) {
    ext += ",ext:" + mode;
  }
  for (const std::string mode : {"crash", "garbage", "outside", "hang", "after-end"})
    ext += " --ext " + mode + "='" + test_optimizer(mode) + "'";
  const auto r =
      harness("--env sphere-10 " + ext + " --seeds 1 --budget 20 --jobs 2 --ext-timeout 2 --db " + db("f.sqlite"));
  // failed runs are results, told by exit status 3 (not 1, a harness failure; not 2, bad input)
  ASSERT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("0 already done, 1 done now, 5 failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("5 runs failed (exit status 3)"), std::string::npos) << r.err;
  const std::map<std::string, std::string> reason = {
      {"ext:crash",
       "ext:crash: closed its stdout and exited with status 3 before the budget end; stderr: "
       "Traceback (most recent call last): | ZeroDivisionError: division by zero"},
      {"ext:garbage", "ext:garbage: malformed line 'this is not json' (not a JSON object)"},
      {"ext:outside", "ext:outside: point 0 of the ask has x[1] = 1.5, outside the box [-1, 1]"},
      {"ext:hang", "ext:hang: no reply within the timeout of 2.0 s (waiting for an ask)"},
      {"ext:after-end", "ext:after-end: asked for points after the budget end"},
  };
  for (const auto& [opt, why] : reason) {
    const auto run = rows(db("f.sqlite"), "SELECT status, episodes, error FROM runs WHERE optimizer='" + opt + "'");
    ASSERT_EQ(run.size(), 1u) << opt;
    EXPECT_EQ(run[0], "failed|" + std::string(opt == "ext:after-end" ? "20" : "3") + "|" + why) << opt;
    // the episodes before the breach are stored
    EXPECT_EQ(
        scalar(db("f.sqlite"), "SELECT count(*) FROM evals e JOIN runs r USING(run_id) WHERE optimizer='" + opt + "'"),
        opt == "ext:after-end" ? "20" : "3");
  }
  // the built-in run beside them is the run it is alone, and the earlier grid is untouched
  EXPECT_EQ(evals_of(db("f.sqlite"), "r.optimizer='random'"), evals_of(db("ref.sqlite")));
  EXPECT_EQ(evals_of(db("f.sqlite"), "r.env='branin'"), before);
  EXPECT_EQ(scalar(db("f.sqlite"), "SELECT count(*) FROM replay"), "0");
  EXPECT_EQ(scalar(db("f.sqlite"), "SELECT count(*) FROM runs WHERE status='running'"), "0");
  // no program is left behind (killed and reaped); the pattern leaves out test_reliability's
  // "hang-ignoring-term", which ctest -j may be running beside this test
  EXPECT_NE(std::system("pgrep -f 'test_optimizer[.]py hang [0-9]' > /dev/null"), 0);
}

TEST_F(ExtCli, BadExternalOptimizerInputExitsTwoBeforeTheDatabase) {
  const std::string grid = "--env sphere-10 --seeds 1 --budget 10 --db " + db("x.sqlite");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--optimizer ext:nope", "optimizer 'ext:nope' needs its command: --ext nope='COMMAND'"},
      {"--optimizer random --ext r='" + test_optimizer("random") + "'",
       "--ext names 'ext:r', which is not in the grid's --optimizer list"},
      {"--optimizer ext:r --ext r", "--ext wants NAME=COMMAND"},
      {"--optimizer ext:a/b --ext a/b=true", "external optimizer name 'a/b' must be"},
      {"--optimizer ext:r --ext r='" + test_optimizer("random") + "' --ext-timeout 0", "--ext-timeout must be"},
      {"--optimizer ext:r --ext r='" + test_optimizer("random") + "' --set ext:r.lr=1",
       "optimizer 'ext:r' has no knobs to --set"},
      {"--optimizer ext:bad --ext bad='" + test_optimizer("bad-probe") + "'",
       "ext:bad: probe of '" + test_optimizer("bad-probe") + "' failed: closed its stdout and exited with status 4"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = harness(grid + " " + args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("harness: error: " + message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(db("x.sqlite"))) << args;
  }
}

TEST_F(ExtCli, TheReportedVersionIsPartOfTheRunKey) {
  const std::string grid = "--env sphere-10 --optimizer ext:r --ext r='" + test_optimizer("random", 4) +
      "' --seeds 1 --budget 12 --quiet --db " + db("v.sqlite");
  ASSERT_EQ(harness(grid, "TEST_OPT_VERSION=1").code, 0);
  const auto again = harness(grid, "TEST_OPT_VERSION=1");
  EXPECT_NE(again.err.find("1 already done, 0 done now"), std::string::npos) << again.err;
  ASSERT_EQ(harness(grid, "TEST_OPT_VERSION=2").code, 0);
  const auto versions = rows(db("v.sqlite"),
                             "SELECT json_extract(c.json, '$.version'), r.status, r.episodes FROM runs r "
                             "JOIN configs c ON c.hash=r.opt_config_hash ORDER BY 1");
  EXPECT_EQ(versions, (std::vector<std::string>{"1|done|12", "2|done|12"}));
}

TEST_F(ExtCli, SigtermMidRunCommitsAndTheResumedRunReplaysToTheSameEvals) {
  const std::string grid =
      "--env cartpole1 --optimizer ext:lbfgsb --seeds 1 --budget 60 --jobs 1 --quiet " + kExamples + " --db ";
  // --ext de is not in this grid: keep only lbfgsb's
  const std::string lbfgsb_only = grid.substr(0, grid.find(" --ext de=")) + " --db ";
  ASSERT_EQ(harness(lbfgsb_only + db("full.sqlite")).code, 0);
  const auto stopped = harness(lbfgsb_only + db("s.sqlite"),
                               "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=25 DSB_FAULT_SIGNAL=15");
  EXPECT_EQ(stopped.code, 143) << stopped.err;
  EXPECT_EQ(scalar(db("s.sqlite"), "SELECT status FROM runs"), "running");
  const auto resumed = harness(lbfgsb_only + db("s.sqlite"));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("resumed 1 interrupted runs"), std::string::npos) << resumed.err;
  EXPECT_EQ(evals_of(db("full.sqlite")), evals_of(db("s.sqlite")));
}

TEST_F(ExtCli, TheRunsCpuCountsTheProgramAndItsChildrenThroughAStopAndItsResume) {
  // test_optimizer.py burn: 0.4 s of CPU in a child it waits for, then 0.02 s before each of its
  // 20 asks; the harness's own share on sphere-2 is milliseconds. Bounds allow 10% for the clock.
  const double burned = 0.4 + 20 * 0.02, burned_by_stop = 0.4 + 10 * 0.02;
  const std::string grid = "--env sphere-2 --optimizer ext:burn --ext burn='" + test_optimizer("burn") +
      "' --seeds 1 --budget 20 --jobs 1 --quiet --db ";
  ASSERT_EQ(harness(grid + db("full.sqlite")).code, 0);
  const auto full = rows(db("full.sqlite"), "SELECT status, cpu_s, wall_s FROM runs");
  ASSERT_EQ(full.size(), 1u);
  const double cpu_full = std::stod(scalar(db("full.sqlite"), "SELECT cpu_s FROM runs"));
  EXPECT_GE(cpu_full, 0.9 * burned) << full[0];
  // the program runs while the harness waits for it: its CPU fits in the run's wall
  EXPECT_LE(cpu_full, std::stod(scalar(db("full.sqlite"), "SELECT wall_s FROM runs")) + 0.05) << full[0];

  // stopped at episode 10: the commit at the stop reads the live program's group from /proc
  const auto stopped =
      harness(grid + db("s.sqlite"), "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=10 DSB_FAULT_SIGNAL=15");
  ASSERT_EQ(stopped.code, 143) << stopped.err;
  EXPECT_EQ(scalar(db("s.sqlite"), "SELECT status FROM runs"), "running");
  const double cpu_stopped = std::stod(scalar(db("s.sqlite"), "SELECT cpu_s FROM runs"));
  EXPECT_GE(cpu_stopped, 0.9 * burned_by_stop);
  // the resume starts the program again (it replays its 10 answered asks), and adds its CPU
  ASSERT_EQ(harness(grid + db("s.sqlite")).code, 0);
  EXPECT_EQ(evals_of(db("s.sqlite")), evals_of(db("full.sqlite")));
  EXPECT_GE(std::stod(scalar(db("s.sqlite"), "SELECT cpu_s FROM runs")), cpu_stopped + 0.9 * burned);
}

TEST_F(ExtCli, SlurmScriptsCarryTheExternalOptimizers) {
  const auto r = harness("slurm --env sphere-10 --optimizer ext:r,random --ext r='" + test_optimizer("random") +
                         "' --ext-timeout 30 --seeds 2 --budget 10 --shards 2 --dir " + (dir_ / "s").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string array = testing::read_file(dir_ / "s" / "array.sbatch");
  EXPECT_NE(array.find("--ext 'r=" + test_optimizer("random") + "' --ext-timeout 30"), std::string::npos) << array;
}

}  // namespace
}  // namespace dsb
