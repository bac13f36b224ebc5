// `harness slurm` never puts a user's file at risk (docs/running.md "Running on a Slurm cluster"),
// through the real `harness` program and its scripts run by bash, as a task or the merge runs on
// a node (no Slurm needed; test `slurm_array` runs them on a real cluster): a --dir holding
// anything the command did not write (a database above all, `--dir .` included) is refused with
// exit 2 and one line, creating nothing; '%' in the folder is written '%%' in #SBATCH lines; the
// merge never writes over results.sqlite, whatever is there (a user's database, a link to one, an
// earlier merge's); a task replaces only the shard file it resumed from.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "support/harness_process.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using testing::read_file;
using testing::scalar;

const std::string kGrid = "--env sphere-2,branin --optimizer random --seeds 2 --budget 5";

// every entry under `root` (links as their targets' names, folders marked), with each file's bytes
std::map<std::string, std::string> tree(const fs::path& root) {
  std::map<std::string, std::string> t;
  if (!fs::exists(root)) return t;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    const std::string rel = fs::relative(e.path(), root).string();
    if (e.is_symlink())
      t[rel] = "link to " + fs::read_symlink(e.path()).string();
    else if (e.is_directory())
      t[rel] = "folder";
    else
      t[rel] = read_file(e.path());
  }
  return t;
}

// runs `sh -c COMMAND` in the background; the caller waits for it (waitpid) or signals it
pid_t start_shell(const std::string& command) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int exit_code(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status); }

class SlurmScripts : public testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args, const std::string& prefix = "") {
    return testing::run_harness(dir_, args, prefix);
  }
  // a user's database (a small done grid) at `p`
  void user_database(const std::string& p) {
    const auto r = harness("--env sphere-3 --optimizer cmaes --seeds 1 --budget 8 --quiet --db " + p);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // exit 2, one line holding `says`, and the test's folder (but the harness's stdout and stderr)
  // exactly as it was
  void expect_refused_unchanged(const std::string& args, const std::string& says, const std::string& prefix = "") {
    fs::create_directories(dir_ / "work");
    const auto before = tree(dir_ / "work");
    const auto r = harness(args, prefix);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << args << ": " << r.err;
    EXPECT_TRUE(tree(dir_ / "work") == before) << args << ": the folder changed";
  }
  std::string work(const std::string& name) const { return (dir_ / "work" / name).string(); }
  // bash SCRIPT as a Slurm node runs it (task `task`, or the merge when task < 0): exit code, log
  int run_script(const std::string& script, int task, std::string* log) {
    fs::create_directories(dir_ / "node");
    const std::string env =
        (task >= 0 ? "SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " " : "") + "TMPDIR=" + (dir_ / "node").string();
    const int status = std::system((env + " bash '" + script + "' > " + path("script.log") + " 2>&1").c_str());
    *log = read_file(path("script.log"));
    return exit_code(status);
  }
};

TEST_F(SlurmScripts, AFolderWithFilesItDidNotWriteIsRefusedAndLeftAsItWas) {
  fs::create_directories(dir_ / "work" / "mine");
  user_database(work("mine/results.sqlite"));
  const std::string slurm = "slurm " + kGrid + " --shards 2 --dir ";
  // the case that lost a user's 54 runs: their results.sqlite in --dir, by name or as `.`
  expect_refused_unchanged(slurm + work("mine"), "holds a SQLite database, '" + work("mine/results.sqlite") + "'");
  expect_refused_unchanged(slurm + ".", "holds a SQLite database", "cd " + work("mine") + " &&");
  expect_refused_unchanged(slurm + work("mine") + "/", "holds a SQLite database");
  // any other file of the user's
  fs::create_directories(dir_ / "work" / "notes");
  { std::ofstream(work("notes/notes.txt")) << "mine\n"; }
  expect_refused_unchanged(slurm + work("notes"),
                           "holds '" + work("notes/notes.txt") + "', which `harness slurm` did not write");
  // a database comes first, whatever the order of the names
  { std::ofstream(work("mine/a-notes.txt")) << "mine\n"; }
  expect_refused_unchanged(slurm + work("mine"), "holds a SQLite database");
  // a file where the folder would be, or above it
  { std::ofstream(work("file")) << "mine\n"; }
  expect_refused_unchanged(slurm + work("file"), "is not a folder");
  expect_refused_unchanged(slurm + work("file/sub"), "cannot create it: '" + work("file") + "' is not a folder");
  // bad flags refuse before the folder is made: nothing is created
  expect_refused_unchanged("slurm " + kGrid + " --shards 0 --dir " + work("new"), "--shards must be from 1");
  expect_refused_unchanged("slurm --env sphere-2 --optimizer nope --seeds 2 --shards 2 --dir " + work("new"), "nope");
  expect_refused_unchanged("slurm " + kGrid + " --shards 2 --time 1 --dir " + work("new"), "--time 1 is under");
  expect_refused_unchanged("slurm " + kGrid + " --shards 2 --dir '" + work("new dir") + "'", "must not contain spaces");
  expect_refused_unchanged("slurm " + kGrid + " --shards 2 --dir " + work("new") + "$(printf '\\033')x",
                           "got '" + work("new") + "\\x1bx'");  // a control character, escaped
  expect_refused_unchanged("slurm " + kGrid + " --shards 2 --time \"$(printf '1\\033[2J')\" --dir " + work("new"),
                           "got '1\\x1b[2J'");
  expect_refused_unchanged("slurm " + kGrid + " --shards 2 --partition \"$(printf 'p\\tq')\" --dir " + work("new"),
                           "got 'p\\tq'");
  EXPECT_FALSE(fs::exists(work("new")));
}

TEST_F(SlurmScripts, ItsOwnFolderIsWrittenAgainButNotBesideForeignFiles) {
  const std::string slurm = "slurm " + kGrid + " --shards 2 --dir " + work("d");
  fs::create_directories(dir_ / "work");
  ASSERT_EQ(harness(slurm).code, 0);
  std::string log;
  ASSERT_EQ(run_script(work("d/array.sbatch"), 0, &log), 0) << log;
  ASSERT_TRUE(fs::exists(work("d/shards/shard-0.sqlite")));
  { std::ofstream(work("d/logs/shard-0-job-7.out")) << "a log\n"; }
  // its scripts, logs and shards: written again
  const auto again = harness(slurm);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find("wrote " + work("d/array.sbatch")), std::string::npos) << again.out;
  // but not for another grid while shards of this one are there
  expect_refused_unchanged("slurm " + kGrid + " --shards 2 --time 1:00:00 --dir " + work("d"),
                           "holds shards of a different grid or binary");
  // a file of the user's in logs/ or shards/, or a link in place of a shard: refused
  { std::ofstream(work("d/logs/mine.txt")) << "mine\n"; }
  expect_refused_unchanged(slurm, "holds '" + work("d/logs/mine.txt") + "'");
  fs::remove(work("d/logs/mine.txt"));
  fs::create_directories(dir_ / "work" / "user");
  user_database(work("user/results.sqlite"));
  fs::rename(work("d/shards/shard-0.sqlite"), work("kept.sqlite"));
  fs::create_symlink(work("user/results.sqlite"), work("d/shards/shard-0.sqlite"));
  expect_refused_unchanged(slurm, "holds a SQLite database, '" + work("d/shards/shard-0.sqlite") + "'");
  fs::remove(work("d/shards/shard-0.sqlite"));
  fs::rename(work("kept.sqlite"), work("d/shards/shard-0.sqlite"));
  // logs/ and shards/ count as its own only beside its array.sbatch
  fs::rename(work("d/array.sbatch"), work("array.sbatch.kept"));
  expect_refused_unchanged(slurm, "holds a SQLite database, '" + work("d/shards/shard-0.sqlite") + "'");
  fs::rename(work("array.sbatch.kept"), work("d/array.sbatch"));
  // a merged results.sqlite, even the merge's own: the merge would never write over it
  ASSERT_EQ(run_script(work("d/array.sbatch"), 1, &log), 0) << log;
  ASSERT_EQ(run_script(work("d/merge.sbatch"), -1, &log), 0) << log;
  expect_refused_unchanged(slurm, "holds a SQLite database, '" + work("d/results.sqlite") + "'");
}

TEST_F(SlurmScripts, PercentInTheFolderIsALiteralPercentInSbatchLines) {
  fs::create_directories(dir_ / "work");
  const std::string d = work("50%a_%j");
  const auto r = harness("slurm " + kGrid + " --shards 2 --dir " + d);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string escaped = work("50%%a_%%j");
  for (const char* script : {"array.sbatch", "merge.sbatch"}) {
    const std::string text = read_file(d + "/" + script);
    std::istringstream lines(text);
    int outputs = 0;
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("#SBATCH --output=", 0) != 0) continue;
      ++outputs;
      EXPECT_EQ(line.rfind("#SBATCH --output=" + escaped + "/logs/", 0), 0u) << line;
      // after the folder only Slurm's own symbols: %a, %A (array), %j (job)
      const std::string tail = line.substr(std::string("#SBATCH --output=").size() + escaped.size());
      EXPECT_TRUE(std::regex_match(tail, std::regex(R"(/logs/(shard-%a-job-%A|merge-job-%j)\.out)"))) << line;
    }
    EXPECT_EQ(outputs, 1) << script;
    // bash gets the folder as it is
    EXPECT_NE(text.find("\ndir=" + d + "\n"), std::string::npos) << script;
  }
  // and the tasks write there: a task and the merge through bash
  std::string log;
  ASSERT_EQ(run_script(d + "/array.sbatch", 0, &log), 0) << log;
  ASSERT_EQ(run_script(d + "/array.sbatch", 1, &log), 0) << log;
  ASSERT_EQ(run_script(d + "/merge.sbatch", -1, &log), 0) << log;
  EXPECT_EQ(scalar(d + "/results.sqlite", "SELECT count(*) FROM runs WHERE status='done'"), "4");
}

TEST_F(SlurmScripts, TheMergeNeverWritesOverAFile) {
  fs::create_directories(dir_ / "work" / "user");
  user_database(work("user/results.sqlite"));
  const std::string user_bytes = read_file(work("user/results.sqlite"));
  ASSERT_EQ(harness("slurm " + kGrid + " --shards 2 --dir " + work("d")).code, 0);
  std::string log;
  for (int task : {0, 1}) ASSERT_EQ(run_script(work("d/array.sbatch"), task, &log), 0) << log;

  // a user's database put there after `harness slurm` wrote the scripts: left byte for byte
  fs::copy_file(work("user/results.sqlite"), work("d/results.sqlite"));
  EXPECT_EQ(run_script(work("d/merge.sbatch"), -1, &log), 1) << log;
  EXPECT_NE(log.find("results.sqlite exists: a merge never writes over a file"), std::string::npos) << log;
  EXPECT_EQ(read_file(work("d/results.sqlite")), user_bytes);
  fs::remove(work("d/results.sqlite"));
  // a link to one: the link stays a link, its target byte for byte
  fs::create_symlink(work("user/results.sqlite"), work("d/results.sqlite"));
  EXPECT_EQ(run_script(work("d/merge.sbatch"), -1, &log), 1) << log;
  EXPECT_TRUE(fs::is_symlink(work("d/results.sqlite")));
  EXPECT_EQ(read_file(work("user/results.sqlite")), user_bytes);
  fs::remove(work("d/results.sqlite"));
  // nothing there: merged
  ASSERT_EQ(run_script(work("d/merge.sbatch"), -1, &log), 0) << log;
  EXPECT_EQ(scalar(work("d/results.sqlite"), "SELECT count(*) FROM runs WHERE status='done'"), "4");
  // its own earlier result: not written over either (a merge is a new file or nothing)
  const std::string merged = read_file(work("d/results.sqlite"));
  EXPECT_EQ(run_script(work("d/merge.sbatch"), -1, &log), 1) << log;
  EXPECT_EQ(read_file(work("d/results.sqlite")), merged);
  // no temporary file left behind by a refused merge
  for (const auto& e : fs::directory_iterator(work("d")))
    EXPECT_EQ(e.path().filename().string().rfind(".results.", 0), std::string::npos) << e.path();
}

class SlurmTaskCopyBack : public SlurmScripts {
 protected:
  // starts task 0 of a one-shard array whose one run hangs in an external optimizer after 3
  // episodes; returns the task's shell once the optimizer hangs
  pid_t start_hanging_task() {
    const std::string pidfile = path("opt.pid");
    fs::remove(pidfile);
    fs::create_directories(dir_ / "node");
    const pid_t task =
        start_shell("SLURM_ARRAY_TASK_ID=0 TMPDIR=" + (dir_ / "node").string() + " TEST_OPT_PIDFILE=" + pidfile +
                    " exec bash " + work("d/array.sbatch") + " > " + path("task.log") + " 2>&1");
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);  // a bound, not a timing
    while (!fs::exists(pidfile) || read_file(pidfile).empty()) {
      if (std::chrono::steady_clock::now() > end || ::waitpid(task, nullptr, WNOHANG) != 0) {
        ADD_FAILURE() << "the task's optimizer never hung: " << read_file(path("task.log"));
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return task;
  }
  // TERM to the task's shell, as Slurm's time limit sends it; its exit code
  int stop(pid_t task) {
    ::kill(task, SIGTERM);
    int status = 0;
    ::waitpid(task, &status, 0);
    return exit_code(status);
  }
  void SetUp() override {
    SlurmScripts::SetUp();
    fs::create_directories(dir_ / "work" / "user");
    user_database(work("user/results.sqlite"));
    const std::string hang =
        "--ext h='/usr/bin/python3 " + std::string(DSB_SOURCE_DIR) + "/tests/ext/test_optimizer.py hang'";
    const auto r = harness("slurm --env sphere-3 --optimizer ext:h --seeds 1 --budget 10 " + hang +
                           " --shards 1 --dir " + work("d"));
    ASSERT_EQ(r.code, 0) << r.err;
  }
};

TEST_F(SlurmTaskCopyBack, AShardThatAppearedWhileTheTaskRanIsLeftAsItIs) {
  const pid_t task = start_hanging_task();
  ASSERT_GT(task, 0);
  fs::copy_file(work("user/results.sqlite"), work("d/shards/shard-0.sqlite"));
  EXPECT_EQ(stop(task), 1);
  const std::string log = read_file(path("task.log"));
  EXPECT_NE(log.find("shard-0.sqlite appeared while this task ran: left as it is"), std::string::npos) << log;
  EXPECT_EQ(read_file(work("d/shards/shard-0.sqlite")), read_file(work("user/results.sqlite")));
  // the task's own copy is kept under its temporary name, with the 3 committed episodes
  const std::smatch kept = [&] {
    std::smatch m;
    std::regex_search(log, m, std::regex(R"(this task's database is (\S+))"));
    return m;
  }();
  ASSERT_FALSE(kept.empty()) << log;
  EXPECT_EQ(scalar(kept[1].str(), "SELECT count(*) FROM evals"), "3");
}

TEST_F(SlurmTaskCopyBack, AShardReplacedWhileTheTaskRanIsLeftAsItIs) {
  // a first attempt stopped by TERM copies back its 3 episodes: the second resumes from that file
  pid_t task = start_hanging_task();
  ASSERT_GT(task, 0);
  ASSERT_EQ(stop(task), 143) << read_file(path("task.log"));
  ASSERT_EQ(scalar(work("d/shards/shard-0.sqlite"), "SELECT count(*) FROM evals"), "3");
  task = start_hanging_task();
  ASSERT_GT(task, 0);
  ASSERT_NE(read_file(path("task.log")).find("resuming from"), std::string::npos);
  // the user's database moved over the shard meanwhile (another file now has the name)
  fs::copy_file(work("user/results.sqlite"), work("user/copy.sqlite"));
  fs::rename(work("user/copy.sqlite"), work("d/shards/shard-0.sqlite"));
  EXPECT_EQ(stop(task), 1);
  const std::string log = read_file(path("task.log"));
  EXPECT_NE(log.find("changed while this task ran (not the file it resumed from): left as it is"), std::string::npos)
      << log;
  EXPECT_EQ(read_file(work("d/shards/shard-0.sqlite")), read_file(work("user/results.sqlite")));
}

TEST_F(SlurmTaskCopyBack, TheShardItResumedFromIsReplacedByItsLongerCopy) {
  pid_t task = start_hanging_task();
  ASSERT_GT(task, 0);
  ASSERT_EQ(stop(task), 143);
  task = start_hanging_task();  // resumes the 3 episodes by replay, hangs again after 3 more asks
  ASSERT_GT(task, 0);
  EXPECT_EQ(stop(task), 143);
  const std::string log = read_file(path("task.log"));
  EXPECT_NE(log.find("copied to " + work("d/shards/shard-0.sqlite")), std::string::npos) << log;
  EXPECT_EQ(scalar(work("d/shards/shard-0.sqlite"), "SELECT count(*) FROM runs"), "1");
}

}  // namespace
}  // namespace dsb
