// The adversarial sweeps' cases, kept (docs/commands.md "Reliability"): every path a command is
// given is looked at without blocking and refused by its kind (a FIFO, a directory, a device)
// with the same words from every command; outputs never take SQLite's names; a newer database
// gets the one message from every command; values are echoed without control characters; a
// database moved while a grid writes it stops the grid, which says where its data is; what an
// external optimizer started ends with its run, detached or not. Each harness runs under
// `timeout`, so a command that blocks again fails its test (exit 124) instead of hanging CI.
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

#include "support/harness_process.hpp"
#include "support/process_watch.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using testing::alive;
using testing::eventually;
using testing::read_file;
using testing::scalar;
using testing::wait_exit_code;

const std::string kSmallGrid = "--env sphere-2,branin --optimizer random,cmaes --seeds 2 --budget 6 --quiet";
// a bound on a command that must not wait for anything, far above what it needs
const std::string kNoHang = "timeout -k 2 20";

class HostileInputs : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args, const std::string& env_prefix = "") {
    return testing::run_harness(dir_, args, env_prefix + " " + kNoHang);
  }
  std::string small_db(const std::string& name) {
    const std::string p = path(name);
    const auto r = harness(kSmallGrid + " --db " + p);
    EXPECT_EQ(r.code, 0) << r.err;
    return p;
  }
  std::string fifo(const std::string& name) {
    const std::string p = path(name);
    EXPECT_EQ(::mkfifo(p.c_str(), 0644), 0);
    return p;
  }
  // exit 2 (not 124: the timeout) with one line that contains `says`
  void expect_refused(const testing::HarnessResult& r, const std::string& says, const std::string& what) {
    EXPECT_EQ(r.code, 2) << what << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << what << ": " << r.err;
  }
};

// ---- 1. a FIFO anywhere a file is read: refused at once, never waited on ----

TEST_F(HostileInputs, AFifoAsATargetIsRefusedByEveryCommand) {
  const std::string f = fifo("target.npy");
  const std::string set = " --set plb-pinch-h5.target=" + f;
  const std::string says = f + ": is a FIFO (named pipe), not a regular file";
  expect_refused(harness("eval --env plb-pinch-h5 --x 0,0,0,0,0,0,0,0,0,0,0,0,0,0,0" + set), says, "eval");
  expect_refused(harness("--env plb-pinch-h5 --optimizer random --budget 2 --quiet --db " + path("g.sqlite") + set),
                 says, "grid");
  expect_refused(harness("plan --env plb-pinch-h5 --optimizer random --budget 2 --db " + path("g.sqlite") + set), says,
                 "plan");
  EXPECT_FALSE(fs::exists(path("g.sqlite")));
}

TEST_F(HostileInputs, AFifoAsADatabaseOrBaselineIsRefusedByEveryCommand) {
  const std::string db = small_db("d.sqlite");
  ASSERT_EQ(harness("export --db " + db + " --out " + path("base.csv")).code, 0);
  const std::string f = fifo("f");
  const std::string says = "'" + f + "' is a FIFO (named pipe), not a regular file";
  expect_refused(harness(kSmallGrid + " --db " + f), "--db: " + says, "grid --db");
  expect_refused(harness("plan " + kSmallGrid + " --db " + f), "--db: " + says, "plan --db");
  expect_refused(harness("export --db " + f + " --out " + path("x.csv")), "--db: " + says, "export --db");
  expect_refused(harness("check --db " + f + " --baseline " + path("base.csv")), "--db: " + says, "check --db");
  expect_refused(harness("check --db " + db + " --baseline " + f), says, "check --baseline");
  expect_refused(harness("report --db " + f + " --out " + path("r")), "--db: " + says, "report --db");
  expect_refused(harness("merge --into " + path("m.sqlite") + " " + f), "merge input: " + says, "merge input");
  expect_refused(harness("merge --into " + f + " " + db), "--into: " + says, "merge --into");
  expect_refused(harness("render --env cartpole1 --best-of " + f + " --out " + path("r.png")), says,
                 "render --best-of");
  for (const char* made : {"x.csv", "r", "m.sqlite", "r.png"}) EXPECT_FALSE(fs::exists(path(made))) << made;
}

TEST_F(HostileInputs, AFolderOrADeviceAsADatabaseIsNamedByItsKind) {
  fs::create_directories(dir_ / "folder");
  const std::string d = path("folder");
  const std::string is_dir = "'" + d + "' is a directory, not a regular file";
  expect_refused(harness("plan " + kSmallGrid + " --db " + d), "--db: " + is_dir, "plan");
  expect_refused(harness(kSmallGrid + " --db " + d), "--db: " + is_dir, "grid");
  expect_refused(harness("merge --into " + path("m.sqlite") + " " + d), "merge input: " + is_dir, "merge");
  expect_refused(harness("report --db " + d + " --out " + path("r")), "--db: " + is_dir, "report");
  expect_refused(harness("export --db " + d + " --out " + path("x.csv")), "--db: " + is_dir, "export");
  expect_refused(harness("check --db " + d + " --baseline " + path("x.csv")), "--db: " + is_dir, "check");
  const std::string is_dev = "'/dev/null' is a character device, not a regular file";
  expect_refused(harness("plan " + kSmallGrid + " --db /dev/null"), "--db: " + is_dev, "plan /dev/null");
  expect_refused(harness("export --db /dev/null --out " + path("x.csv")), "--db: " + is_dev, "export /dev/null");
  expect_refused(harness("report --db /dev/null --out " + path("r")), "--db: " + is_dev, "report /dev/null");
  const auto missing = harness("export --db " + path("none.sqlite") + " --out " + path("x.csv"));
  expect_refused(missing, "--db: '" + path("none.sqlite") + "': no such file", "a missing database");
}

TEST_F(HostileInputs, AFifoNobodyReadsIsRefusedAsAnOutput) {
  const std::string db = small_db("d.sqlite");
  const std::string f = fifo("out.csv");
  expect_refused(harness("export --db " + db + " --out " + f), "is a FIFO (named pipe) that nobody reads",
                 "export --out");
  // one that is read gets the table as a pipe does
  std::string got;
  std::thread reader([&] { got = read_file(f); });  // blocks until a writer opens it
  const auto r = harness("export --db " + db + " --out " + f);
  EXPECT_EQ(r.code, 0) << r.err;
  if (r.code != 0) {  // let the reader go
    std::ofstream unblock(f);
  }
  reader.join();
  EXPECT_EQ(got.rfind("env,optimizer,seed,", 0), 0u) << got;
}

// ---- 2. outputs never take the names SQLite gives the files beside a database ----

TEST_F(HostileInputs, SqliteSidecarNamesAreRefusedAsOutputsWhetherOrNotTheyExist) {
  const std::string db = small_db("d.sqlite");
  for (const char* suffix : {"-journal", "-wal", "-shm"}) {
    const std::string out = path(std::string("new.sqlite") + suffix);
    expect_refused(harness("export --db " + db + " --out " + out), std::string("ends in '") + suffix + "'", suffix);
    EXPECT_FALSE(fs::exists(out)) << suffix;
  }
}

// ---- 2b. a command that only reads a database leaves no file beside it ----

namespace {
// the SQLite files in `dir` beside its databases, by name
std::vector<std::string> sidecar_files(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    for (const std::string suffix : {"-journal", "-wal", "-shm"})
      if (name.size() > suffix.size() && name.ends_with(suffix)) found.push_back(name);
  }
  std::sort(found.begin(), found.end());
  return found;
}
}  // namespace

TEST_F(HostileInputs, ACommandThatOnlyReadsADatabaseLeavesItsFolderAsItFoundIt) {
  const std::string db = small_db("d.sqlite");
  ASSERT_EQ(sidecar_files(dir_), std::vector<std::string>{}) << "the grid's own close removes its -wal and -shm";
  const std::string before = read_file(db);
  // SQLite's read-only connection to a WAL database made a -wal and a -shm and could not remove them
  // (export and check left both until 2026-12-06)
  const std::vector<std::string> reads = {
      "export --db " + db + " --out " + path("x.csv"),
      "export --db " + db + " --format ioh --out " + path("ioh"),
      "check --db " + db + " --baseline " + path("x.csv"),
      "merge --into " + path("m.sqlite") + " " + db,
      "plan " + kSmallGrid + " --db " + db,
  };
  for (const auto& args : reads) {
    const auto r = harness(args);
    EXPECT_EQ(r.code, 0) << args << ": " << r.err;
    EXPECT_EQ(sidecar_files(dir_), std::vector<std::string>{}) << args;
  }
  EXPECT_EQ(read_file(db), before);

  // where another connection has the database open, its -wal and -shm are left as they were
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open_v2(db.c_str(), &other, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "SELECT count(*) FROM runs", nullptr, nullptr, nullptr), SQLITE_OK);
  const std::vector<std::string> held = {"d.sqlite-shm", "d.sqlite-wal"};
  ASSERT_EQ(sidecar_files(dir_), held);
  const auto r = harness("export --db " + db + " --out " + path("y.csv"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(read_file(path("y.csv")), read_file(path("x.csv")));
  EXPECT_EQ(sidecar_files(dir_), held);
  sqlite3_close(other);
  EXPECT_EQ(sidecar_files(dir_), std::vector<std::string>{}) << "the last connection's close removes them";
  EXPECT_EQ(read_file(db), before);
}

// ---- 3. a database of a newer schema: one message from every command ----

TEST_F(HostileInputs, ANewerSchemaGetsTheSameMessageFromEveryCommand) {
  const std::string db = small_db("d.sqlite");
  ASSERT_EQ(harness("export --db " + db + " --out " + path("base.csv")).code, 0);
  testing::execute(db, "UPDATE meta SET value='99' WHERE key='schema_version'");
  const std::string before = read_file(db);
  const std::string says = "has schema_version 99, newer than this harness";
  expect_refused(harness(kSmallGrid + " --db " + db), says, "grid");
  expect_refused(harness("plan " + kSmallGrid + " --db " + db), says, "plan");
  expect_refused(harness("export --db " + db + " --out " + path("x.csv")), says, "export");
  expect_refused(harness("export --db " + db + " --format ioh --out " + path("ioh")), says, "export ioh");
  expect_refused(harness("check --db " + db + " --baseline " + path("base.csv")), says, "check");
  expect_refused(harness("merge --into " + path("m.sqlite") + " " + db), says, "merge");
  EXPECT_EQ(read_file(db), before);
}

// ---- 4. values are echoed without control characters ----

TEST_F(HostileInputs, ControlCharactersInEchoedValuesAreEscaped) {
  const auto r = harness("eval --env \"$(printf 'sphere-2\\033[2J\\nforged')\" --x 0,0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.find('\x1b'), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("sphere-2\\x1b[2J\\nforged"), std::string::npos) << r.err;
}

TEST_F(HostileInputs, NumbersOutsideTheDoublesSayWhichWayTheyFallOut) {
  expect_refused(harness("eval --env sphere-2 --x 1e-400,0"), "'1e-400' underflows a double", "1e-400");
  expect_refused(harness("eval --env sphere-2 --x 1e400,0"), "'1e400' overflows a double", "1e400");
  // a subnormal number is a number
  const auto r = harness("eval --env sphere-2 --x 1e-310,0");
  EXPECT_EQ(r.code, 0) << r.err;
}

// ---- 5. a database moved while a grid writes it ----

TEST_F(HostileInputs, ADatabaseMovedWhileAGridWritesItStopsTheGridWhichSaysWhereItsDataIs) {
  // run 1 (random on sphere-2) ends done; run 2, an external optimizer, hangs after 3 episodes
  const std::string db = path("mv.sqlite"), moved = path("moved.sqlite");
  const std::string opt = "/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py hang";
  const std::string cmd = "TEST_OPT_PIDFILE=" + path("opt.pid") + " exec " + DSB_HARNESS_EXE +
      " --env sphere-2 --optimizer random,ext:stuck --ext stuck='" + opt +
      "' --ext-timeout 600 --seeds 1 --budget 20 --jobs 2 --quiet --db " + db + " > /dev/null 2> " + path("err") +
      " < /dev/null";
  const pid_t h = ::fork();
  if (h == 0) {
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_TRUE(eventually([&] { return fs::exists(path("opt.pid")); }, std::chrono::seconds(60)));
  ASSERT_TRUE(
      eventually([&] { return testing::quiet_scalar(db, "SELECT count(*) FROM runs WHERE status='done'") == "1"; },
                 std::chrono::seconds(60)));
  fs::rename(db, moved);
  ::kill(h, SIGTERM);  // the stopped run commits its episodes: the commit finds the path moved
  const int code = wait_exit_code(h);
  EXPECT_NE(code, 0);
  EXPECT_NE(code, 143);  // not the plain stop: the grid failed
  const std::string err = read_file(path("err"));
  EXPECT_NE(err.find("was moved or replaced while this harness wrote it"), std::string::npos) << err;
  EXPECT_NE(err.find("is in '" + moved + "'"), std::string::npos) << err;
  EXPECT_EQ(err.find("done now"), std::string::npos) << err;
  // the done run is in the moved file, complete, and nothing new appeared under the old name
  EXPECT_EQ(scalar(moved, "SELECT count(*) FROM runs WHERE status='done'"), "1");
  EXPECT_EQ(scalar(moved, "SELECT count(*) FROM evals e JOIN runs r USING(run_id) WHERE r.status='done'"), "20");
  EXPECT_FALSE(fs::exists(db));
}

// ---- 6. what an external optimizer starts ends with its run ----

TEST_F(HostileInputs, ADetachedChildOfAnExternalOptimizerEndsWithItsRun) {
  // after 3 episodes the optimizer starts a child in a session of its own, holding its stdout,
  // and exits 3
  const std::string pidfile = path("detached.pid");
  const std::string opt =
      "/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py leak-detached";
  const auto r = harness("--env sphere-2 --optimizer ext:leaky --ext leaky='" + opt +
                             "' --ext-timeout 5 --seeds 1 --budget 8 --quiet --db " + path("e.sqlite"),
                         "TEST_OPT_PIDFILE=" + pidfile);
  EXPECT_EQ(r.code, 3) << r.err;  // the run fails alone
  ASSERT_TRUE(fs::exists(pidfile));
  const pid_t detached = std::stoi(read_file(pidfile));
  EXPECT_TRUE(eventually([&] { return !alive(detached); }, std::chrono::seconds(10)))
      << "the detached child (pid " << detached << ") outlived its run";
  if (alive(detached)) ::kill(detached, SIGKILL);
}

}  // namespace
}  // namespace dsb
