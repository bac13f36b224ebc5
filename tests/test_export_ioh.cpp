// `harness export --format ioh` end to end, through the real program: a tiny grid, exported in
// IOHprofiler's format; the JSON meta files parse and name the right functions, dimensions,
// algorithms and runs; every .dat row's raw_y is the database's loss of that episode, bit for bit,
// and the rows are exactly the improvements of the best loss; runs of one optimizer at two
// budgets are two algorithms; bad --format, a used --out and an unreadable database exit 2.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>

#include "harness/store/result_table.hpp"
#include "support/harness_process.hpp"
#include "support/sqlite_rows.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

class ExportIoh : public dsb::testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args) { return testing::run_harness(dir_, args); }

  // the small grid of these tests: 2 envs x 2 optimizers x 2 seeds x 20 episodes
  void run_grid(const std::string& db, const std::string& extra = "--optimizer random,cmaes --budget 20") {
    const auto r = harness("--env sphere-10,branin " + extra + " --seeds 2 --quiet --db " + db);
    ASSERT_EQ(r.code, 0) << r.err;
  }
};

// (env, optimizer, seed, budget) -> losses by episode (NULL as NaN) of the done runs
using RunKey = std::tuple<std::string, std::string, int, std::int64_t>;
std::map<RunKey, std::vector<double>> read_losses(const std::string& path) {
  std::map<RunKey, std::vector<double>> losses;
  for (const auto& [k, loss] : testing::stored_losses(path, "r.status = 'done'")) {
    const auto& [env, optimizer, seed, budget, episode] = k;
    auto& v = losses[RunKey{env, optimizer, seed, budget}];
    EXPECT_EQ(static_cast<std::int64_t>(v.size()), episode);  // episodes 0, 1, ... in order
    v.push_back(loss);
  }
  return losses;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// a .dat file: one block of (evaluations, raw_y) rows per run, each after its header line
std::vector<std::vector<std::pair<std::int64_t, double>>> read_dat(const fs::path& p) {
  std::ifstream in(p);
  EXPECT_TRUE(in.good()) << p;
  std::vector<std::vector<std::pair<std::int64_t, double>>> blocks;
  std::string line;
  while (std::getline(in, line)) {
    if (line == "evaluations raw_y") {
      blocks.emplace_back();
      continue;
    }
    EXPECT_FALSE(blocks.empty()) << "row before the first header: " << line;
    std::istringstream s(line);
    std::string e, y;
    s >> e >> y;
    EXPECT_TRUE(s.eof() || (s >> std::ws).eof()) << line;
    char* end = nullptr;
    const double v = std::strtod(y.c_str(), &end);
    EXPECT_EQ(*end, '\0') << line;
    if (!blocks.empty()) blocks.back().emplace_back(std::stoll(e), v);
  }
  return blocks;
}

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  EXPECT_TRUE(in.good()) << p;
  return nlohmann::json::parse(in);  // throws (fails the test) when it is not JSON
}

std::set<std::string> names_in(const fs::path& folder) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(folder)) names.insert(e.path().filename().string());
  return names;
}

TEST_F(ExportIoh, MetaFilesAndDataRowsMatchTheDatabaseBitForBit) {
  const std::string db = path("grid.sqlite"), out = path("ioh");
  run_grid(db);
  const auto r = harness("export --db " + db + " --out " + out + " --format ioh");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("wrote 8 runs"), std::string::npos) << r.err;

  // one folder per algorithm; function ids are positions in the sorted env names
  EXPECT_EQ(names_in(out), (std::set<std::string>{"cmaes", "random"}));
  const std::map<std::string, std::pair<int, int>> functions = {{"branin", {1, 2}}, {"sphere-10", {2, 10}}};
  const auto losses = read_losses(db);
  ASSERT_EQ(losses.size(), 8u);
  std::size_t rows_checked = 0, runs_checked = 0;
  for (const std::string algorithm : {"cmaes", "random"}) {
    const fs::path folder = fs::path(out) / algorithm;
    EXPECT_EQ(names_in(folder),
              (std::set<std::string>{"IOHprofiler_f1_branin.json", "data_f1_branin", "IOHprofiler_f2_sphere-10.json",
                                     "data_f2_sphere-10"}));
    for (const auto& [env, id_dim] : functions) {
      const auto [fid, dim] = id_dim;
      const auto meta = read_json(folder / ("IOHprofiler_f" + std::to_string(fid) + "_" + env + ".json"));
      EXPECT_EQ(meta.at("suite"), "diffsim-bench");
      EXPECT_EQ(meta.at("function_id"), fid);
      EXPECT_EQ(meta.at("function_name"), env);
      EXPECT_EQ(meta.at("maximization"), false);
      EXPECT_EQ(meta.at("algorithm").at("name"), algorithm);
      EXPECT_TRUE(meta.at("algorithm").at("info").is_string());
      EXPECT_EQ(meta.at("attributes"), nlohmann::json({"evaluations", "raw_y"}));
      ASSERT_EQ(meta.at("scenarios").size(), 1u);
      const auto& scenario = meta.at("scenarios")[0];
      EXPECT_EQ(scenario.at("dimension"), dim);
      const std::string dat = scenario.at("path");
      EXPECT_EQ(dat,
                "data_f" + std::to_string(fid) + "_" + env + "/IOHprofiler_f" + std::to_string(fid) + "_DIM" +
                    std::to_string(dim) + ".dat");
      const auto blocks = read_dat(folder / dat);
      const auto& runs = scenario.at("runs");
      ASSERT_EQ(runs.size(), 2u);
      ASSERT_EQ(blocks.size(), runs.size());
      for (std::size_t k = 0; k < runs.size(); ++k) {
        const auto& run = runs[k];
        const int seed = run.at("instance");
        EXPECT_EQ(seed, static_cast<int>(k));  // ordered by seed
        EXPECT_EQ(run.at("evals"), 20);
        const auto it = losses.find({env, algorithm, seed, 20});
        ASSERT_NE(it, losses.end()) << env << " " << algorithm << " " << seed;
        const auto& loss = it->second;
        // the rows are the improvements of the best loss, each the episode's loss bit for bit
        std::vector<std::pair<std::int64_t, double>> want;
        for (std::size_t e = 0; e < loss.size(); ++e)
          if (!std::isnan(loss[e]) && (want.empty() || loss[e] < want.back().second))
            want.emplace_back(static_cast<std::int64_t>(e) + 1, loss[e]);
        const auto& got = blocks[k];
        ASSERT_EQ(got.size(), want.size()) << env << " " << algorithm << " seed " << seed;
        ASSERT_FALSE(got.empty());
        for (std::size_t i = 0; i < got.size(); ++i) {
          EXPECT_EQ(got[i].first, want[i].first);
          EXPECT_TRUE(same_bits(got[i].second, loss[got[i].first - 1]))
              << env << " " << algorithm << " seed " << seed << " evaluation " << got[i].first << ": " << got[i].second
              << " vs " << loss[got[i].first - 1];
          ++rows_checked;
        }
        // best: the last improvement, with a point of the env's dimension
        const auto& best = run.at("best");
        EXPECT_EQ(best.at("evals"), got.back().first);
        EXPECT_TRUE(same_bits(best.at("y").get<double>(), got.back().second));
        EXPECT_EQ(best.at("x").size(), static_cast<std::size_t>(dim));
        ++runs_checked;
      }
    }
  }
  EXPECT_EQ(runs_checked, 8u);
  EXPECT_GE(rows_checked, 16u);
  std::cout << "checked " << runs_checked << " runs, " << rows_checked << " rows bit for bit\n";
}

TEST_F(ExportIoh, CsvIsTheDefaultAndUnchanged) {
  const std::string db = path("grid.sqlite");
  run_grid(db);
  ASSERT_EQ(harness("export --db " + db + " --out " + path("a.csv")).code, 0);
  ASSERT_EQ(harness("export --db " + db + " --out " + path("b.csv") + " --format csv").code, 0);
  const std::string a = testing::read_file(path("a.csv"));
  EXPECT_EQ(a, testing::read_file(path("b.csv")));
  EXPECT_EQ(a.rfind(std::string(kResultTableHeader) + "\n", 0), 0u);
  EXPECT_EQ(std::count(a.begin(), a.end(), '\n'), 1 + 8 * 20);
}

TEST_F(ExportIoh, OneOptimizerAtTwoBudgetsIsTwoAlgorithms) {
  const std::string db = path("grid.sqlite"), out = path("ioh");
  run_grid(db);
  run_grid(db, "--optimizer cmaes --budget 10");
  const auto r = harness("export --db " + db + " --out " + out + " --format ioh");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(names_in(out), (std::set<std::string>{"cmaes-b10", "cmaes-b20", "random"}));
  const auto meta = read_json(fs::path(out) / "cmaes-b10" / "IOHprofiler_f2_sphere-10.json");
  EXPECT_EQ(meta.at("algorithm").at("name"), "cmaes-b10");
  EXPECT_EQ(meta.at("scenarios")[0].at("runs")[0].at("evals"), 10);
}

TEST_F(ExportIoh, BadInputExitsTwoWithOneLineNamingIt) {
  const std::string db = path("grid.sqlite");
  run_grid(db);
  auto one_line = [](const std::string& s) { return std::count(s.begin(), s.end(), '\n') == 1; };

  auto r = harness("export --db " + db + " --out " + path("x") + " --format parquet");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("'parquet'"), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r.err)) << r.err;
  EXPECT_FALSE(fs::exists(path("x")));

  fs::create_directories(path("used"));
  std::ofstream(path("used") + "/keep.txt") << "mine\n";
  r = harness("export --db " + db + " --out " + path("used") + " --format ioh");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("used")), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r.err)) << r.err;
  EXPECT_EQ(names_in(path("used")), std::set<std::string>{"keep.txt"});

  r = harness("export --db " + db + " --out " + path("grid.sqlite") + " --format ioh");  // a file
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("not a folder"), std::string::npos) << r.err;

  fs::create_directories(path("empty"));  // an empty folder is accepted
  r = harness("export --db " + db + " --out " + path("empty") + " --format ioh");
  EXPECT_EQ(r.code, 0) << r.err;

  r = harness("export --db " + path("missing.sqlite") + " --out " + path("y") + " --format ioh");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("missing.sqlite")), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("y")));

  std::ofstream(path("junk.sqlite")) << "not a database at all, just text long enough to be a header..\n";
  r = harness("export --db " + path("junk.sqlite") + " --out " + path("z") + " --format ioh");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("junk.sqlite")), std::string::npos) << r.err;
  EXPECT_TRUE(one_line(r.err)) << r.err;
  EXPECT_FALSE(fs::exists(path("z")));
}

}  // namespace
}  // namespace dsb
