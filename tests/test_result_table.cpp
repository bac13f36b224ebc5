// Regression gate on result tables: `harness export` writes the baseline format, `harness check`
// passes on equal tables and fails with a readable diff when one loss differs in its last digit,
// a row is missing or a row is added; a malformed baseline exits 2; a result that changed while
// its results versions did not is named as a silent change.
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "harness/store/result_table.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

class ResultTable : public dsb::testing::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    db_ = path("r.sqlite");
    csv_ = path("base.csv");
    ASSERT_EQ(run("--env sphere-2,branin --optimizer random,cmaes --seeds 2 --budget 7 --quiet --db " + db_), 0);
    ASSERT_EQ(run("export --db " + db_ + " --out " + csv_), 0);
  }

  int run(const std::string& args) {
    const auto r = dsb::testing::run_harness(dir_, args);
    out_ = r.out;
    err_ = r.err;
    return r.code;
  }
  std::vector<std::string> lines() {
    std::istringstream in(dsb::testing::read_file(csv_));
    std::vector<std::string> v;
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
  }
  void write(const std::vector<std::string>& v) {
    std::ofstream out(csv_);
    for (const auto& l : v) out << l << "\n";
  }
  int check() { return run("check --db " + db_ + " --baseline " + csv_); }

  std::string db_, csv_, out_, err_;
};

TEST_F(ResultTable, ExportWritesOneRowPerEpisodeWith17Digits) {
  const auto v = lines();
  ASSERT_EQ(v.size(), 1u + 2 * 2 * 2 * 7);
  EXPECT_EQ(v[0], kResultTableHeader);
  // a loss round-trips: 17 significant digits
  const auto rows = read_result_csv(csv_);
  for (const auto& r : rows) {
    const double x = std::stod(r.loss);
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    EXPECT_EQ(r.loss, buf);
  }
}

TEST_F(ResultTable, CheckPassesOnEqualTables) {
  EXPECT_EQ(check(), 0) << out_;
  EXPECT_NE(out_.find("56 rows equal, 0 changed, 0 missing, 0 added"), std::string::npos) << out_;
}

TEST_F(ResultTable, OneLossDifferingInTheLastDigitFails) {
  auto v = lines();
  // change the last digit of the loss on line 5
  std::string& l = v[5];
  char& last = l.back();
  last = last == '1' ? '2' : '1';
  write(v);
  EXPECT_EQ(check(), 1);
  EXPECT_NE(out_.find("1 changed"), std::string::npos) << out_;
  EXPECT_NE(out_.find("->"), std::string::npos) << out_;
}

TEST_F(ResultTable, MissingAndAddedRowsFail) {
  auto v = lines();
  const std::string removed = v[3];
  v.erase(v.begin() + 3);
  write(v);
  EXPECT_EQ(check(), 1);
  EXPECT_NE(out_.find("1 added"), std::string::npos) << out_;  // in the database, not the baseline
  EXPECT_NE(out_.find(removed), std::string::npos) << out_;

  v = lines();
  v.push_back("branin,random,9,7,aaaa,bbbb,1,1,1,0,1.5");
  write(v);
  EXPECT_EQ(check(), 1);
  EXPECT_NE(out_.find("1 missing"), std::string::npos) << out_;  // in the baseline, not the database
}

TEST_F(ResultTable, MalformedBaselineExitsTwoWithOneLine) {
  const std::string h = std::string(kResultTableHeader) + "\n";
  for (const std::string& bad : std::vector<std::string>{
           "not,a,header\n", h + "branin,random,x,7,a,b,1,1,1,0,1.5\n", h + "branin,random,0,7,a,b,1,1,1,0\n",
           h + "branin,random,0,7,a,b,1,1,1,0,1.5zz\n", h + "branin,random,0,7,a,b,1,x,1,0,1.5\n",
           // a table from before results versions
           "env,optimizer,seed,budget,env_config_hash,opt_config_hash,episode,loss\n"}) {
    { std::ofstream(csv_) << bad; }
    EXPECT_EQ(check(), 2) << bad;
    EXPECT_EQ(std::count(err_.begin(), err_.end(), '\n'), 1) << err_;
    EXPECT_NE(err_.find("base.csv"), std::string::npos) << err_;
  }
  EXPECT_EQ(run("check --db " + (dir_ / "none.sqlite").string() + " --baseline " + csv_), 2);
}

// The gate catches a silent change: one stored loss changed in a copy of the baseline, its
// versions unchanged, is a result that changed without a version bump; the message names the env
// and the optimizer, says "bump its results version" and gives the command that regenerates the
// baseline. A row whose versions differ asks only for the baseline to be regenerated.
TEST_F(ResultTable, ASilentChangeNamesTheEnvAndOptimizerAndAsksForABump) {
  auto v = lines();
  const auto rows = read_result_csv(csv_);
  std::size_t at = 0;
  for (std::size_t k = 1; k < v.size(); ++k)
    if (v[k].rfind("sphere-2,cmaes,", 0) == 0) at = k;
  ASSERT_GT(at, 0u);
  v[at] = v[at].substr(0, v[at].rfind(',') + 1) + "0.125";  // one loss of sphere-2 / cmaes
  write(v);
  EXPECT_EQ(check(), 1);
  EXPECT_NE(out_.find("check: sphere-2 / cmaes: 1 results changed while its results versions did not (env 1, "
                      "optimizer 1, run 1): bump its results version"),
            std::string::npos)
      << out_;
  EXPECT_NE(out_.find("then regenerate the baseline: harness export --db " + db_ + " --out " + csv_ + " --force"),
            std::string::npos)
      << out_;
  EXPECT_EQ(out_.find("branin /"), std::string::npos) << out_;  // only the pair that changed

  // the same row with another optimizer version in the baseline: a bump, so a regeneration
  v = lines();
  auto f = v[at];
  // fields: env,optimizer,seed,budget,env hash,opt hash,env_version,optimizer_version,...
  std::size_t comma = 0;
  for (int k = 0; k < 7; ++k) comma = f.find(',', comma) + 1;
  v[at] = f.substr(0, comma) + "7" + f.substr(f.find(',', comma));
  write(v);
  EXPECT_EQ(check(), 1);
  EXPECT_NE(out_.find("check: sphere-2 / cmaes: results versions env 1, optimizer 7, run 1 -> env 1, optimizer 1, "
                      "run 1 (1 rows): regenerate the baseline"),
            std::string::npos)
      << out_;
  EXPECT_EQ(out_.find("bump its results version"), std::string::npos) << out_;
}

}  // namespace
}  // namespace dsb
