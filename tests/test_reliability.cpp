// What the harness guarantees to a user who makes mistakes (docs/commands.md "Reliability"), each through
// the real `harness` program on real files, the earlier ways each one lost or mixed results
// re-run: no command writes over a database (whatever path names it) or over another file
// without --force; one writer per database file whatever the path; canonical env names; exit
// codes a script can use; signals reach external optimizers at once and a killed harness leaves
// no orphan; read-only inputs; --threads capped; merge strict whatever the input order; messages
// that say the truth.
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "common/usable_cpus.hpp"
#include "support/harness_process.hpp"
#include "support/process_watch.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using testing::alive;
using testing::eventually;
using testing::execute;
using testing::read_file;
using testing::rows;
using testing::scalar;
using testing::start_harness;
using testing::wait_exit_code;
using testing::wait_until;
using Clock = std::chrono::steady_clock;

const std::string kSmallGrid = "--env sphere-2,branin --optimizer random,cmaes --seeds 2 --budget 6 --quiet";

class Reliability : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args, const std::string& env_prefix = "") {
    return testing::run_harness(dir_, args, env_prefix);
  }
  // a database of a small done grid
  std::string small_db(const std::string& name) {
    const std::string p = path(name);
    const auto r = harness(kSmallGrid + " --db " + p);
    EXPECT_EQ(r.code, 0) << r.err;
    return p;
  }
  // exit 2 with one line that contains `says`
  void expect_refused(const testing::HarnessResult& r, const std::string& says, const std::string& what) {
    EXPECT_EQ(r.code, 2) << what << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << what << ": " << r.err;
  }
  // the files of the test's folder but the harness's own stdout and stderr
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string n = e.path().filename().string();
      if (n != "stdout" && n != "stderr") names.push_back(n);
    }
    std::sort(names.begin(), names.end());
    return names;
  }
};

// ---- 1. no command writes over a database, or over another file without --force ----

TEST_F(Reliability, NoOutputGoesOverADatabaseWhateverPathNamesItEvenWithForce) {
  const std::string b = small_db("b.sqlite");
  const std::string other = small_db("other.sqlite");
  fs::create_symlink(b, path("link.sqlite"));
  fs::create_hard_link(b, path("hard.sqlite"));
  fs::create_hard_link(b, path("hard.png"));  // render wants a .png name
  const std::string bytes = read_file(b), other_bytes = read_file(other);
  const std::string rel = "cd " + dir_.string() + " &&";
  struct Case {
    std::string args, prefix;
  };
  const std::vector<Case> cases = {
      {"export --db " + b + " --out " + b, ""},
      {"export --db b.sqlite --out ./b.sqlite", rel},
      {"export --db " + b + " --out " + path("link.sqlite"), ""},
      {"export --db " + b + " --out " + path("hard.sqlite"), ""},
      {"export --db " + b + " --out " + other, ""},
      {"export --db " + b + " --out " + other + " --force", ""},
      {"export --db " + b + " --out " + b + " --force", ""},
      {"export --db " + b + " --format ioh --out " + b + " --force", ""},
      {"landscape --env sphere-2 --dims 0,1 --res 3 --out " + b, ""},
      {"landscape --env sphere-2 --dims 0,1 --res 3 --out " + path("link.sqlite") + " --force", ""},
      {"render --env bounce --x 0.1,0.2,0.3 --frames 1 --out " + path("hard.png") + " --force", ""},
      {"report --db " + b + " --out " + b, ""},
  };
  for (const auto& c : cases) {
    const auto r = harness(c.args, c.prefix);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find("database"), std::string::npos) << c.args << ": " << r.err;
  }
  // the databases are the bytes they were, and still databases the harness reads
  EXPECT_EQ(read_file(b), bytes);
  EXPECT_EQ(read_file(other), other_bytes);
  ASSERT_EQ(harness("export --db " + path("link.sqlite") + " --out " + path("t.csv")).code, 0);
  EXPECT_NE(read_file(path("t.csv")).find("sphere-2"), std::string::npos);
}

TEST_F(Reliability, NoOutputGoesOverTheWriteAheadLogOfALiveDatabase) {
  const std::string b = small_db("b.sqlite");
  // a writer that keeps its log: a -wal file with frames beside the database
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(b.c_str(), &h), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(h, "PRAGMA wal_autocheckpoint=0; INSERT INTO meta(key, value) VALUES ('test', 'x');", nullptr,
                         nullptr, nullptr),
            SQLITE_OK);
  ASSERT_GT(fs::file_size(b + "-wal"), 0u);
  const std::string wal = read_file(b + "-wal");
  for (const std::string side : {"-wal", "-shm"}) {
    const auto r = harness("export --db " + b + " --out " + b + side + " --force");
    expect_refused(r, "ends in '" + side + "', a name SQLite gives the files beside a database", side);
  }
  EXPECT_EQ(read_file(b + "-wal"), wal);
  sqlite3_close(h);
}

TEST_F(Reliability, AnExistingFileIsWrittenOverOnlyWithForceAndOutputsAppearWhole) {
  const std::string b = small_db("b.sqlite");
  { std::ofstream(path("mine.csv")) << "my notes\n"; }
  { std::ofstream(path("mine.png")) << "my picture\n"; }
  fs::create_symlink(path("mine.csv"), path("link.csv"));
  fs::create_symlink(path("nowhere.csv"), path("dangling.csv"));
  for (const std::string& args :
       {"export --db " + b + " --out " + path("mine.csv"), "export --db " + b + " --out " + path("link.csv"),
        "export --db " + b + " --out " + path("dangling.csv"),
        "landscape --env sphere-2 --dims 0,1 --res 3 --out " + path("mine.csv"),
        "render --env bounce --x 0.1,0.2,0.3 --frames 1 --out " + path("mine.png")})
    expect_refused(harness(args), "exists; give --force", args);
  EXPECT_EQ(read_file(path("mine.csv")), "my notes\n");
  EXPECT_EQ(read_file(path("mine.png")), "my picture\n");
  EXPECT_FALSE(fs::exists(path("nowhere.csv")));
  // with --force the file is replaced, whole, and the output is the same as into a new file
  ASSERT_EQ(harness("export --db " + b + " --out " + path("mine.csv") + " --force").code, 0);
  ASSERT_EQ(harness("export --db " + b + " --out " + path("fresh.csv")).code, 0);
  EXPECT_EQ(read_file(path("mine.csv")), read_file(path("fresh.csv")));
  EXPECT_NE(read_file(path("fresh.csv")).find("sphere-2"), std::string::npos);
  ASSERT_EQ(harness("render --env bounce --x 0.1,0.2,0.3 --frames 1 --force --out " + path("mine.png")).code, 0);
  EXPECT_EQ(read_file(path("mine.png")).substr(1, 3), "PNG");
  // outputs appear whole: no temporary file is left beside them, after success or refusal
  for (const auto& f : files()) EXPECT_EQ(f.find(".tmp-"), std::string::npos) << f;
  // devices are written as they go: --out /dev/null needs no --force
  EXPECT_EQ(harness("export --db " + b + " --out /dev/null").code, 0);
}

TEST_F(Reliability, OutputFoldersMustBeNewEmptyOrMadeByTheHarness) {
  const std::string b = small_db("b.sqlite");
  fs::create_directories(dir_ / "mine");
  { std::ofstream(dir_ / "mine" / "index.html") << "<p>my page</p>\n"; }
  expect_refused(harness("report --db " + b + " --out " + path("mine")), "with other files in it", "report");
  expect_refused(harness(kSmallGrid + " --db " + path("g.sqlite") + " --report " + path("mine")),
                 "with other files in it", "grid --report");
  EXPECT_FALSE(fs::exists(path("g.sqlite")));  // refused before the grid opened its database
  expect_refused(harness("export --db " + b + " --format ioh --out " + path("mine")), "with other files in it", "ioh");
  EXPECT_EQ(read_file(dir_ / "mine" / "index.html"), "<p>my page</p>\n");
  // a report folder is the harness's own: made, then made again
  ASSERT_EQ(harness("report --db " + b + " --out " + path("rep")).code, 0);
  ASSERT_EQ(harness("report --db " + b + " --out " + path("rep")).code, 0);
  // slurm --dir: a script of the user's of the same name is not replaced
  fs::create_directories(dir_ / "cluster");
  { std::ofstream(dir_ / "cluster" / "submit.sh") << "echo mine\n"; }
  expect_refused(harness("slurm --env sphere-2 --optimizer random --seeds 2 --shards 2 --dir " + path("cluster")),
                 "not written by `harness slurm`", "slurm");
  EXPECT_EQ(read_file(dir_ / "cluster" / "submit.sh"), "echo mine\n");
}

// ---- 2. one writer per database file, whatever the path ----

TEST_F(Reliability, TheLockBelongsToTheFileNotItsName) {
  const std::string grid = "--env cartpole3 --optimizer cmaes --seeds 2 --budget 20000 --jobs 1 --quiet";
  const std::string db = path("l.sqlite");
  const pid_t first = start_harness(grid + " --db " + db);
  ASSERT_GT(first, 0);
  // a run 'running' with a committed prefix (commits come every 2 s; on a loaded machine the first
  // may come late, and the checks below need a journal to find intact)
  const bool started = wait_until(db, "SELECT count(*) FROM runs WHERE status='running' AND episodes > 0", "1", first,
                                  std::chrono::seconds(120));
  if (!started) ::kill(first, SIGKILL);
  ASSERT_TRUE(started) << "no run row 'running' with committed episodes appeared";
  fs::create_symlink(db, path("sym.sqlite"));
  fs::create_hard_link(db, path("hard.sqlite"));
  const std::string holder = "is in use by another harness (pid " + std::to_string(first);
  expect_refused(harness(grid + " --db " + path("sym.sqlite")), holder, "symlink");
  expect_refused(harness(grid + " --db " + path("hard.sqlite")), holder, "hard link");
  expect_refused(harness(grid + " --db ./l.sqlite", "cd " + dir_.string() + " &&"), holder, "relative path");
  expect_refused(harness("merge --into " + path("hard.sqlite") + " " + small_db("s.sqlite")), holder, "merge");
  // none of them opened the database: no second write-ahead log, no lock file beside it
  EXPECT_FALSE(fs::exists(path("hard.sqlite-wal")));
  EXPECT_FALSE(fs::exists(path("sym.sqlite-wal")));
  EXPECT_FALSE(fs::exists(db + "-lock"));
  ::kill(first, SIGTERM);
  EXPECT_EQ(wait_exit_code(first), 143);
  // the first harness's run is intact: one run, 'running', a whole prefix with its journal
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs"), "1");
  EXPECT_EQ(scalar(db, "SELECT episodes = (SELECT count(*) FROM evals) FROM runs"), "1");
  EXPECT_NE(scalar(db, "SELECT count(*) FROM replay"), "0");
  EXPECT_EQ(scalar(db, "PRAGMA integrity_check"), "ok");
}

// ---- 3. canonical env names ----

TEST_F(Reliability, HorizonVariantsHaveOneNameEach) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"fluid-h05", "is written 'fluid-h5'"},         {"fluid-h005", "is written 'fluid-h5'"},
      {"plb-pinch-h05", "is written 'plb-pinch-h5'"}, {"fluid-h50", "name it 'fluid'"},
      {"plb-rope-h50", "name it 'plb-rope'"},         {"fluid-h7", "a multiple of 5 from 5 to 45"},
      {"fluid-h+5", "unknown env 'fluid-h+5'"},       {"plb-pinch-h", "unknown env 'plb-pinch-h'"},
  };
  for (const auto& [name, says] : cases) {
    expect_refused(harness("eval --env " + name + " --x 0"), says, name);
    expect_refused(harness("plan --env fluid-h5," + name + " --optimizer random --seeds 1"), says, "plan " + name);
  }
  // the canonical names work
  const auto p = harness("plan --env fluid-h5,plb-pinch-h45,fluid --optimizer random --seeds 1");
  EXPECT_EQ(p.code, 0) << p.err;
  EXPECT_NE(p.out.find("3 to run"), std::string::npos) << p.out;
}

// ---- 4. exit codes a script can use ----

TEST_F(Reliability, AGridWithFailedRunsExitsThreeAndPlanNamesThem) {
  const std::string crash =
      " --ext crash='/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py crash 1'";
  const std::string grid = "--env sphere-3 --optimizer random,ext:crash --seeds 2 --budget 10 --quiet" + crash;
  const auto r = harness(grid + " --db " + path("f.sqlite"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("2 runs failed (exit status 3)"), std::string::npos) << r.err;
  EXPECT_EQ(scalar(path("f.sqlite"), "SELECT count(*) FROM runs WHERE status='failed'"), "2");
  // plan --db says which, with the error
  const auto p = harness("plan " + grid + " --db " + path("f.sqlite"));
  EXPECT_EQ(p.code, 0) << p.err;
  EXPECT_NE(p.out.find("failed in the database: 2 of these runs"), std::string::npos) << p.out;
  EXPECT_NE(p.out.find("sphere-3/ext:crash/seed 0/"), std::string::npos) << p.out;
  EXPECT_NE(p.out.find("ext:crash: closed its stdout and exited with status 3"), std::string::npos) << p.out;
  // a grid whose runs are all done exits 0
  EXPECT_EQ(harness("--env sphere-3 --optimizer random --seeds 2 --budget 10 --quiet --db " + path("f.sqlite")).code,
            0);
}

TEST_F(Reliability, TheSlurmArrayTakesFailedRunsAsResults) {
  // the array task's script itself (bash, no cluster needed): a shard whose grid has a failed run
  // succeeds, so the merge that depends on it runs; the failed run is in the shard's database
  const std::string crash =
      "--ext crash='/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py crash 1'";
  ASSERT_EQ(harness("slurm --env sphere-3 --optimizer ext:crash --seeds 1 --budget 10 " + crash + " --shards 1 --dir " +
                    path("c"))
                .code,
            0);
  const int status = std::system(("SLURM_ARRAY_TASK_ID=0 TMPDIR=" + dir_.string() + " bash " + path("c/array.sbatch") +
                                  " > " + path("task.log") + " 2>&1")
                                     .c_str());
  const std::string log = read_file(path("task.log"));
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << log;
  EXPECT_NE(log.find("harness exit status 3"), std::string::npos) << log;
  EXPECT_NE(log.find("some runs failed"), std::string::npos) << log;
  EXPECT_EQ(scalar(path("c/shards/shard-0.sqlite"), "SELECT status FROM runs"), "failed");
}

// ---- 5. signals reach external optimizers at once; no orphan after SIGKILL ----

class ExternalSignals : public Reliability {
 protected:
  // a grid whose one run hangs in an external optimizer that ignores SIGTERM, after 3 episodes,
  // with a reply timeout far beyond Slurm's 30 s grace; returns the harness's pid and the
  // optimizer's (written by it once it hangs)
  std::pair<pid_t, pid_t> start_hung_grid() {
    const std::string opt =
        "/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py hang-ignoring-term 1";
    const pid_t h = start_harness("--env sphere-3 --optimizer ext:stuck --ext stuck='" + opt +
                                      "' --ext-timeout 600 --seeds 1 --budget 20 --quiet --db " + path("s.sqlite"),
                                  "TEST_OPT_PIDFILE=" + path("opt.pid"));
    pid_t opt_pid = 0;
    eventually([&] { return fs::exists(path("opt.pid")); }, std::chrono::seconds(60));
    if (fs::exists(path("opt.pid"))) opt_pid = std::stoi(read_file(path("opt.pid")));
    return {h, opt_pid};
  }
};

TEST_F(ExternalSignals, SigtermEndsTheHarnessWellInsideSlurmsGraceAndTheRunResumesLater) {
  const auto [h, opt] = start_hung_grid();
  ASSERT_GT(opt, 0) << "the optimizer never hung";
  ASSERT_TRUE(alive(opt));
  const auto t0 = Clock::now();
  ::kill(h, SIGTERM);
  const int code = wait_exit_code(h);
  const double took = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(code, 143);
  // TERM is ignored, so this is the grace (3 s) and a kill: far below --ext-timeout's 600 s and
  // Slurm's 30 s (a bound on a behaviour, not a speed measurement)
  EXPECT_LT(took, 20.0);
  EXPECT_FALSE(alive(opt));
  // the run is interrupted, not failed: its episodes are committed and the same command resumes it
  EXPECT_EQ(scalar(path("s.sqlite"), "SELECT status || ' ' || episodes FROM runs"), "running 3");
  EXPECT_EQ(scalar(path("s.sqlite"), "SELECT count(*) FROM evals"), "3");
}

TEST_F(ExternalSignals, AKilledHarnessLeavesNoOrphan) {
  const auto [h, opt] = start_hung_grid();
  ASSERT_GT(opt, 0) << "the optimizer never hung";
  ::kill(h, SIGKILL);
  EXPECT_EQ(wait_exit_code(h), 128 + SIGKILL);
  EXPECT_TRUE(eventually([&] { return !alive(opt); }, std::chrono::seconds(30)))
      << "the external optimizer (pid " << opt << ") outlived the killed harness";
}

// ---- 6. read-only inputs ----

// a finished database in a folder the commands cannot write: as another user, or on a read-only
// mount; every command that only reads it works, and writes nothing beside it
class ReadOnlyInputs : public Reliability {
 protected:
  void SetUp() override {
    Reliability::SetUp();
    const std::string source = small_db("source.sqlite");
    ASSERT_EQ(harness("export --db " + source + " --out " + path("expected.csv")).code, 0);
    // a copy of the file alone, as a finished grid leaves it (its log checkpointed and removed; the
    // export, a reader, may have left an empty -wal beside the source)
    fs::create_directories(dir_ / "ro");
    db_ = path("ro/r.sqlite");
    ASSERT_TRUE(!fs::exists(source + "-wal") || fs::file_size(source + "-wal") == 0);
    fs::copy_file(source, db_);
    fs::create_directories(dir_ / "out");
    fs::permissions(dir_ / "out", fs::perms::all);  // writable for whoever runs the commands
    fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_exec | fs::perms::others_exec);
  }
  // every reading command on the read-only database, run with `prefix` (a user or a mount)
  void expect_reading_works(const std::string& prefix, const std::string& what) {
    const std::string out = path("out") + "/" + what;
    const auto e = harness("export --db " + db_ + " --out " + out + ".csv", prefix);
    EXPECT_EQ(e.code, 0) << what << ": " << e.err;
    EXPECT_EQ(read_file(out + ".csv"), read_file(path("expected.csv"))) << what;
    const auto c = harness("check --db " + db_ + " --baseline " + path("expected.csv"), prefix);
    EXPECT_EQ(c.code, 0) << what << ": " << c.out << c.err;
    const auto p = harness("plan " + kSmallGrid + " --db " + db_, prefix);
    EXPECT_EQ(p.code, 0) << what << ": " << p.err;
    EXPECT_NE(p.out.find("8 runs in the grid; 8 already done"), std::string::npos) << what << ": " << p.out;
    const auto r = harness("report --db " + db_ + " --out " + out + "-report", prefix);
    EXPECT_EQ(r.code, 0) << what << ": " << r.out << r.err;
    const auto m = harness("merge --into " + out + "-merged.sqlite " + db_, prefix);
    EXPECT_EQ(m.code, 0) << what << ": " << m.err;
    const auto i = harness("export --db " + db_ + " --format ioh --out " + out + "-ioh", prefix);
    EXPECT_EQ(i.code, 0) << what << ": " << i.err;
    // nothing was written beside the database
    std::vector<std::string> beside;
    for (const auto& f : fs::directory_iterator(dir_ / "ro")) beside.push_back(f.path().filename().string());
    EXPECT_EQ(beside, std::vector<std::string>{"r.sqlite"}) << what;
  }
  std::string db_;
};

TEST_F(ReadOnlyInputs, ADatabaseTheUserMayNotWrite) {
  fs::permissions(dir_ / "ro",
                  fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read | fs::perms::group_exec |
                      fs::perms::others_read | fs::perms::others_exec);
  fs::permissions(db_, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  // root may write anything: the commands then run as nobody
  const std::string prefix = ::geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups" : "";
  expect_reading_works(prefix, "unwritable");
  fs::permissions(dir_ / "ro", fs::perms::owner_all);
}

TEST_F(ReadOnlyInputs, ADatabaseTheUserMayNotWriteInAFolderTheyMay) {
  // the folder lets the user make files, the database does not let them write it: SQLite's read of
  // it would make -wal and -shm files it cannot remove
  fs::permissions(dir_ / "ro", fs::perms::all);
  fs::permissions(db_, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  const std::string prefix = ::geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups" : "";
  expect_reading_works(prefix, "unwritable-file");
  fs::permissions(dir_ / "ro", fs::perms::owner_all);
}

TEST_F(ReadOnlyInputs, AReadOnlyMount) {
  // a read-only bind mount of the database's folder in a private mount namespace (root only)
  const std::string ro = (dir_ / "ro").string();
  if (::geteuid() != 0 ||
      std::system(("unshare -m sh -c 'mount --bind " + ro + " " + ro + " && mount -o remount,bind,ro " + ro + " " + ro +
                   "' > /dev/null 2>&1")
                      .c_str()) != 0)
    GTEST_SKIP() << "no private read-only mount here (needs root and mount namespaces)";
  const std::string prefix = "unshare -m sh -c 'mount --bind " + ro + " " + ro + " && mount -o remount,bind,ro " + ro +
      " && exec \"$0\" \"$@\"'";
  expect_reading_works(prefix, "mount");
}

// ---- 7. threads within reason ----

TEST_F(Reliability, ThreadsAreCappedAtTheUsableCpus) {
  const int cpus = usable_cpus();
  const auto r = harness("--env sphere-2 --optimizer random --seeds 1 --budget 3 --threads " +
                         std::to_string(cpus + 1) + " --db " + path("t.sqlite"));
  expect_refused(r, "--threads " + std::to_string(cpus + 1) + " is more than the " + std::to_string(cpus) + " CPUs",
                 "threads");
  EXPECT_FALSE(fs::exists(path("t.sqlite")));
  EXPECT_EQ(harness("--env sphere-2 --optimizer random --seeds 1 --budget 3 --quiet --threads " + std::to_string(cpus) +
                    " --db " + path("t.sqlite"))
                .code,
            0);
  // planning for another machine is not capped
  EXPECT_EQ(harness("plan --env sphere-2 --optimizer random --threads 64").code, 0);
}

// ---- 8. merge is strict everywhere ----

class StrictMerge : public Reliability {
 protected:
  // a copy of one 'running' run of random on sphere-3, stopped after `episodes` committed
  std::string running_copy(const std::string& name, int episodes) {
    const auto r = harness("--env sphere-3 --optimizer random --seeds 1 --budget 40 --quiet --db " + path(name),
                           "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=" + std::to_string(episodes) +
                               " DSB_FAULT_SIGNAL=15 DSB_FAULT_COMMIT_EVERY_EPISODE=1");
    EXPECT_EQ(r.code, 143) << r.err;
    return path(name);
  }
  // the merged database's runs and evals, ids and wall times aside
  std::vector<std::string> content(const std::string& db) {
    auto r = rows(db,
                  "SELECT env, optimizer, seed, status, episodes, best_loss, error, host FROM runs ORDER BY env, "
                  "optimizer, seed");
    for (const auto& e : rows(db,
                              "SELECT r.optimizer, e.episode, e.loss, e.wall_s FROM evals e JOIN runs r "
                              "USING(run_id) ORDER BY r.optimizer, e.episode"))
      r.push_back(e);
    return r;
  }
};

TEST_F(StrictMerge, UnfinishedCopiesThatDifferWhereBothHaveEpisodesConflict) {
  const std::string a = running_copy("a.sqlite", 10), b = running_copy("b.sqlite", 20);
  const std::string further = scalar(b, "SELECT episodes FROM runs");
  ASSERT_GT(std::stoi(further), std::stoi(scalar(a, "SELECT episodes FROM runs")));
  // consistent: the further copy is kept, whatever the order
  ASSERT_EQ(harness("merge --into " + path("ab.sqlite") + " " + a + " " + b).code, 0);
  ASSERT_EQ(harness("merge --into " + path("ba.sqlite") + " " + b + " " + a).code, 0);
  EXPECT_EQ(scalar(path("ab.sqlite"), "SELECT episodes FROM runs"), further);
  EXPECT_EQ(content(path("ab.sqlite")), content(path("ba.sqlite")));
  // one loss changed inside the shared prefix: a conflict naming both inputs, and no output file
  execute(a, "UPDATE evals SET loss = loss + 1 WHERE episode = 4");
  const auto r = harness("merge --into " + path("c.sqlite") + " " + a + " " + b);
  expect_refused(r, "conflicts with its copy from '" + a + "'", "running copies");
  EXPECT_NE(r.err.find("in '" + b + "'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("c.sqlite")));
  EXPECT_FALSE(fs::exists(path("c.sqlite-wal")));
}

TEST_F(StrictMerge, FailedCopiesResolveTheSameWayWhateverTheInputOrder) {
  const std::string crash =
      " --ext crash='/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py crash 1'";
  const std::string grid = "--env sphere-3 --optimizer ext:crash --seeds 1 --budget 10 --quiet" + crash;
  ASSERT_EQ(harness(grid + " --db " + path("a.sqlite")).code, 3);
  ASSERT_EQ(harness(grid + " --db " + path("b.sqlite")).code, 3);
  ASSERT_EQ(harness(grid + " --db " + path("c.sqlite")).code, 3);
  // copies that failed differently: another host and error text, and one failed earlier
  execute(path("b.sqlite"), "UPDATE runs SET host = 'elsewhere', error = 'ext:crash: no reply within the timeout'");
  execute(path("c.sqlite"), "DELETE FROM evals WHERE episode = 2; UPDATE runs SET episodes = 2, host = 'third'");
  const std::vector<std::string> a_b_c = {path("a.sqlite"), path("b.sqlite"), path("c.sqlite")};
  std::vector<std::vector<std::string>> merged;
  std::vector<std::string> order = a_b_c;
  std::sort(order.begin(), order.end());
  int i = 0;
  do {
    const std::string out = path("m" + std::to_string(i++) + ".sqlite");
    std::string args = "merge --into " + out;
    for (const auto& f : order) args += " " + f;
    const auto r = harness(args);
    ASSERT_EQ(r.code, 0) << r.err;
    merged.push_back(content(out));
  } while (std::next_permutation(order.begin(), order.end()));
  for (const auto& m : merged) EXPECT_EQ(m, merged[0]);
  // the further of the copies (3 episodes) is kept
  EXPECT_EQ(scalar(path("m0.sqlite"), "SELECT episodes FROM runs"), "3");
}

TEST_F(StrictMerge, ErrorsNameTheInputAtFaultAndARefusedMergeLeavesNoFile) {
  const std::string good = small_db("good.sqlite");
  const std::string broken = small_db("broken.sqlite");
  execute(broken, "DELETE FROM configs");
  const auto r = harness("merge --into " + path("out.sqlite") + " " + good + " " + broken);
  expect_refused(r, "merge: input '" + broken + "'", "no configs");
  EXPECT_NE(r.err.find("which its configs table lacks"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out.sqlite")));
  // a file that is not a database
  { std::ofstream(path("notes.txt")) << "not a database\n"; }
  expect_refused(harness("merge --into " + path("out.sqlite") + " " + good + " " + path("notes.txt")),
                 "merge: input '" + path("notes.txt") + "'", "not a database");
  EXPECT_FALSE(fs::exists(path("out.sqlite")));
  // into an existing database, a refused merge changes nothing
  const std::string into = small_db("into.sqlite");
  const std::string before = read_file(into);
  execute(good, "UPDATE evals SET loss = loss * 3 WHERE episode = 1");
  expect_refused(harness("merge --into " + into + " " + good), "conflicts with its copy from the output", "conflict");
  EXPECT_EQ(read_file(into), before);
}

// ---- 9. messages say the truth ----

TEST_F(Reliability, RangeMessagesSayWhatIsAccepted) {
  const std::string grid = "--env sphere-2 --optimizer random --seeds 1 --budget 2 --quiet --db " + path("m.sqlite");
  expect_refused(harness(grid + " --jobs -1"), "--jobs must be from 1 to 1024, or 0 for the CPUs", "--jobs");
  EXPECT_EQ(harness(grid + " --jobs 0").code, 0);  // 0 is accepted, as the message says
  const std::string ext = " --optimizer ext:r --ext r='/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) +
      "/tests/ext/test_optimizer.py random 1'";
  expect_refused(harness("--env sphere-2 --seeds 1 --budget 2 --db " + path("e.sqlite") + ext + " --ext-timeout 0"),
                 "--ext-timeout must be seconds above 0 and at most 86400, got '0'", "--ext-timeout");
}

}  // namespace
}  // namespace dsb
