// Regression gate on result tables: `harness export` writes the baseline format, `harness check`
// passes on equal tables and fails with a readable diff when one loss differs in its last digit,
// a row is missing or a row is added; a malformed baseline exits 2.
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "harness/result_table.hpp"
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
  v.push_back("branin,random,9,7,aaaa,bbbb,0,1.5");
  write(v);
  EXPECT_EQ(check(), 1);
  EXPECT_NE(out_.find("1 missing"), std::string::npos) << out_;  // in the baseline, not the database
}

TEST_F(ResultTable, MalformedBaselineExitsTwoWithOneLine) {
  for (const std::string& bad : std::vector<std::string>{"not,a,header\n", std::string(kResultTableHeader) + "\nbranin,random,x,7,a,b,0,1.5\n",
                                std::string(kResultTableHeader) + "\nbranin,random,0,7,a,b,0\n",
                                std::string(kResultTableHeader) + "\nbranin,random,0,7,a,b,0,1.5zz\n"}) {
    { std::ofstream(csv_) << bad; }
    EXPECT_EQ(check(), 2) << bad;
    EXPECT_EQ(std::count(err_.begin(), err_.end(), '\n'), 1) << err_;
    EXPECT_NE(err_.find("base.csv"), std::string::npos) << err_;
  }
  EXPECT_EQ(run("check --db " + (dir_ / "none.sqlite").string() + " --baseline " + csv_), 2);
}

}  // namespace
}  // namespace dsb
