// Run diagnostics (runs.diagnostics). The building blocks (summaries, capped lists); an optimizer
// whose list outgrows the cap; then the harness binary on a small branin grid, the stored JSON
// checked against what the evals and configs of the same runs say (episode accounting, IPOP
// restarts and stop reasons, the GP refit schedule, NLopt return codes, gradient-norm counts), and
// a rerun with another --jobs giving identical JSON; and the command line refusing a newer or a
// foreign database (exit 2, the file untouched).
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>

#include "optimizers/core/diagnostics.hpp"
#include "optimizers/nlopt_adapters.hpp"
#include "tests/support/test_functions.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------------------------
// building blocks

TEST(DiagnosticsBlocks, SummaryOfOddEvenAndEmptyLists) {
  EXPECT_EQ(summarize(std::vector<double>{3.0, 1.0, 2.0}),
            json({{"count", 3}, {"min", 1.0}, {"median", 2.0}, {"max", 3.0}}));
  EXPECT_EQ(summarize(std::vector<int>{4, 1, 3, 2}), json({{"count", 4}, {"min", 1}, {"median", 2.5}, {"max", 4}}));
  EXPECT_EQ(summarize(std::vector<double>{}),
            json({{"count", 0}, {"min", nullptr}, {"median", nullptr}, {"max", nullptr}}));
}

TEST(DiagnosticsBlocks, CappedListKeepsTheFirstEntriesAndCountsTheRest) {
  std::vector<int> items(250);
  for (int i = 0; i < 250; ++i) items[i] = 1000 + i;
  json out;
  put_capped(out, "list", items, [](int v, std::size_t i) { return json{{"v", v}, {"i", i}}; });
  ASSERT_EQ(out["list"].size(), kDiagnosticsListCap);
  EXPECT_EQ(out["list"][99], json({{"v", 1099}, {"i", 99}}));
  EXPECT_EQ(out["list_truncated"], 150);
  json small;
  put_capped(small, "list", std::vector<int>{7}, [](int v, std::size_t) { return v; });
  EXPECT_EQ(small, json({{"list", {7}}, {"list_truncated", 0}}));
}

// L-BFGS restarts on a quadratic end every few episodes: a long run has many more starts than
// the cap, and its diagnostics stay small and count them all
TEST(DiagnosticsBlocks, NloptStartListIsCappedAndItsBlobStaysSmall) {
  auto f = testing::shifted_sphere_objective(4, 3000, 0.3, 0.1);
  NloptOptimizer opt(nlopt_lbfgs_defaults());
  Rng rng(7);
  EXPECT_THROW(opt.minimize(f, rng), BudgetExhausted);
  const json d = opt.diagnostics();
  const auto starts = opt.last_run().starts.size();
  ASSERT_GT(starts, kDiagnosticsListCap);
  EXPECT_EQ(d["starts"], starts);
  EXPECT_EQ(d["start_list"].size(), kDiagnosticsListCap);
  EXPECT_EQ(d["start_list_truncated"], starts - kDiagnosticsListCap);
  std::size_t counted = 0;
  for (const auto& [name, n] : d["results"].items()) counted += n.get<std::size_t>();
  EXPECT_EQ(counted, starts);
  EXPECT_LT(d.dump().size(), 8192u) << d.dump().size();
}

// ---------------------------------------------------------------------------------------------
// the harness binary

using Result = dsb::testing::HarnessResult;
using dsb::testing::read_file;

class DiagnosticsCli : public dsb::testing::TempDirTest {
 protected:
  Result harness(const std::string& args) { return dsb::testing::run_harness(dir_, args); }
  std::string db(const std::string& name) { return path(name); }
};

// one run with what its evals and config say, and its stored diagnostics
struct StoredRun {
  std::string status;
  std::int64_t budget = 0, episodes = 0, failed_episodes = 0, grad_evals = 0, failed_grad_evals = 0;
  json opt_config, diagnostics;
  std::string diagnostics_text;
};
using RunId = std::tuple<std::string, std::string, int>;  // env, optimizer, seed

std::map<RunId, StoredRun> read_runs(const std::string& path) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* q = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, R"sql(
    SELECT r.env, r.optimizer, r.seed, r.status, r.budget, r.episodes, r.failed_episodes, c.json,
           r.diagnostics,
           (SELECT count(*) FROM evals e WHERE e.run_id = r.run_id AND e.used_grad = 1),
           (SELECT count(*) FROM evals e WHERE e.run_id = r.run_id AND e.used_grad = 1 AND e.failed = 1)
    FROM runs r JOIN configs c ON c.hash = r.opt_config_hash)sql",
                               -1, &q, nullptr),
            SQLITE_OK)
      << sqlite3_errmsg(db);
  auto text = [&](int c) {
    const auto* p = sqlite3_column_text(q, c);
    return p ? std::string(reinterpret_cast<const char*>(p)) : std::string();
  };
  std::map<RunId, StoredRun> runs;
  while (sqlite3_step(q) == SQLITE_ROW) {
    StoredRun r;
    r.status = text(3);
    r.budget = sqlite3_column_int64(q, 4);
    r.episodes = sqlite3_column_int64(q, 5);
    r.failed_episodes = sqlite3_column_int64(q, 6);
    r.opt_config = json::parse(text(7));
    r.diagnostics_text = text(8);
    r.diagnostics = r.diagnostics_text.empty() ? json() : json::parse(r.diagnostics_text);
    r.grad_evals = sqlite3_column_int64(q, 9);
    r.failed_grad_evals = sqlite3_column_int64(q, 10);
    runs[{text(0), text(1), sqlite3_column_int(q, 2)}] = std::move(r);
  }
  sqlite3_finalize(q);
  sqlite3_close(db);
  return runs;
}

// The objective half: episodes, failures and gradients as the evals table has them.
void check_objective_side(const std::string& who, const StoredRun& r) {
  const json& o = r.diagnostics["objective"];
  EXPECT_EQ(o["episodes"], r.episodes) << who;
  EXPECT_EQ(o["episodes"], r.budget) << who;
  EXPECT_EQ(o["failed_episodes"], r.failed_episodes) << who;
  EXPECT_EQ(o["grad_episodes"], r.grad_evals) << who;
  const json& g = o["grad_norms"];
  // one norm per gradient episode that did not fail
  EXPECT_EQ(g["count"], r.grad_evals - r.failed_grad_evals) << who;
  if (g["count"] == 0) {
    EXPECT_TRUE(g["min"].is_null() && g["median"].is_null() && g["max"].is_null()) << who;
    EXPECT_EQ(g["zero"], 0) << who;
  } else {
    const double lo = g["min"], mid = g["median"], hi = g["max"];
    EXPECT_TRUE(0.0 <= lo && lo <= mid && mid <= hi && std::isfinite(hi)) << who << ": " << g.dump();
    EXPECT_LE(g["zero"].get<std::int64_t>(), g["count"].get<std::int64_t>()) << who;
    EXPECT_EQ(g["zero"].get<std::int64_t>() > 0, lo == 0.0) << who;
  }
}

void check_cmaes(const std::string& who, const StoredRun& r, int dim) {
  const json& d = r.diagnostics["optimizer"];
  const json& inst = d["instances"];
  ASSERT_GE(d["restarts"].get<int>(), 1) << who << ": the budget should force an IPOP restart";
  ASSERT_EQ(inst.size(), d["restarts"].get<std::size_t>() + 1) << who;
  EXPECT_EQ(d["instances_truncated"], 0) << who;
  const std::set<std::string> stops = {"numerical",     "tolfun",       "tolx",        "tolxup",
                                       "noeffectcoord", "noeffectaxis", "conditioncov"};
  // population 4 + floor(3 ln n), times ipop_factor per restart
  int lambda = r.opt_config["population"].get<int>() > 0 ? r.opt_config["population"].get<int>()
                                                         : 4 + static_cast<int>(std::floor(3.0 * std::log(dim)));
  std::int64_t told = 0, generations = 0;
  for (std::size_t i = 0; i < inst.size(); ++i) {
    EXPECT_EQ(inst[i]["population"], lambda) << who << " instance " << i;
    const std::string stop = inst[i]["stop"];
    if (i + 1 < inst.size())
      EXPECT_TRUE(stops.count(stop)) << who << " instance " << i << " stopped by '" << stop << "'";
    else
      EXPECT_EQ(stop, "budget") << who;
    told += inst[i]["generations"].get<std::int64_t>() * lambda;
    generations += inst[i]["generations"].get<std::int64_t>();
    lambda = static_cast<int>(std::round(lambda * r.opt_config["ipop_factor"].get<double>()));
  }
  EXPECT_EQ(d["generations"], generations) << who;
  // every episode belongs to a told generation, except a last generation cut by the budget
  const int last_lambda = inst.back()["population"];
  EXPECT_LE(told, r.episodes) << who;
  EXPECT_LT(r.episodes - told, last_lambda) << who;
  const double sigma = d["final_sigma"];
  EXPECT_TRUE(sigma > 0.0 && std::isfinite(sigma)) << who;
}

// the number of GP fits the schedule of optimizers/bo/bo.hpp gives for `episodes` points
int expected_bo_fits(const json& cfg, int dim, std::int64_t episodes) {
  const int n_init =
      cfg["initial_points"].get<int>() > 0 ? cfg["initial_points"].get<int>() : std::clamp(dim + 1, 5, 20);
  const int every_until = cfg["refit_every_until"];
  const double growth = cfg["refit_growth"];
  int fits = 0, last = 0;
  for (int n = n_init; n <= episodes; ++n) {
    if (n == n_init || n <= every_until || n >= static_cast<int>(std::ceil((1.0 + growth) * last))) {
      ++fits;
      last = n;
    }
  }
  return fits;
}

void check_bo(const std::string& who, const StoredRun& r, int dim) {
  const json& d = r.diagnostics["optimizer"];
  EXPECT_EQ(d["points"], r.episodes) << who;
  EXPECT_EQ(d["failed_points"], r.failed_episodes) << who;
  EXPECT_EQ(d["gp_fits"], expected_bo_fits(r.opt_config, dim, r.episodes)) << who;
  EXPECT_EQ(d["gp_fit_failures"], 0) << who;
  const json& h = d["hyperparameters"];
  ASSERT_EQ(h["lengthscales"].size(), static_cast<std::size_t>(dim)) << who;
  for (const auto& l : h["lengthscales"]) EXPECT_GT(l.get<double>(), 0.0) << who;
  EXPECT_GT(h["outputscale"].get<double>(), 0.0) << who;
  EXPECT_GE(h["noise"].get<double>(), r.opt_config["gp"]["noise_floor"].get<double>()) << who;
}

void check_boleap(const std::string& who, const StoredRun& r, int dim) {
  const json& d = r.diagnostics["optimizer"];
  const json& leaps = d["leap_list"];
  ASSERT_GE(d["leaps"].get<int>(), 1) << who;
  ASSERT_EQ(leaps.size(), d["leaps"].get<std::size_t>()) << who;
  const json& bo = r.opt_config["bo"];
  const int n_init = bo["initial_points"].get<int>() > 0 ? bo["initial_points"].get<int>() : std::clamp(dim + 1, 5, 20);
  std::int64_t episodes = n_init, descents = 0, steps = 0;
  for (std::size_t i = 0; i < leaps.size(); ++i) {
    const json& l = leaps[i];
    EXPECT_LE(l["episodes"].get<int>(), r.opt_config["episodes_per_leap"].get<int>()) << who;
    episodes += l["episodes"].get<std::int64_t>();
    descents += l["descents"].get<std::int64_t>();
    steps += l["descent_steps"].get<std::int64_t>();
    const std::string ended = l["ended"];
    if (i + 1 < leaps.size())
      EXPECT_TRUE(ended == "episode_cap" || ended.rfind("cma:", 0) == 0) << who << ": " << ended;
    else
      EXPECT_EQ(ended, "budget") << who;
    if (l["descents"] > 0) {
      EXPECT_LE(l["best_loss"].get<double>(), l["end_loss"].get<double>()) << who;
    }
  }
  // every episode is in the initial design or a leap; every gradient episode is a descent step
  EXPECT_EQ(episodes, r.episodes) << who;
  EXPECT_EQ(d["descents"], descents) << who;
  EXPECT_EQ(d["descent_steps"]["count"], descents) << who;
  EXPECT_EQ(steps, r.grad_evals) << who;
  EXPECT_LE(d["stale_stops"].get<std::int64_t>(), descents) << who;
  EXPECT_GE(d["gp"]["gp_fits"].get<int>(), 1) << who;
}

void check_nlopt(const std::string& who, const StoredRun& r) {
  const json& d = r.diagnostics["optimizer"];
  const std::set<std::string> names = {"NLOPT_FAILURE",          "NLOPT_INVALID_ARGS",   "NLOPT_OUT_OF_MEMORY",
                                       "NLOPT_ROUNDOFF_LIMITED", "NLOPT_FORCED_STOP",    "NLOPT_SUCCESS",
                                       "NLOPT_STOPVAL_REACHED",  "NLOPT_FTOL_REACHED",   "NLOPT_XTOL_REACHED",
                                       "NLOPT_MAXEVAL_REACHED",  "NLOPT_MAXTIME_REACHED"};
  ASSERT_GE(d["starts"].get<int>(), 1) << who;
  ASSERT_EQ(d["start_list_truncated"], 0) << who;
  ASSERT_EQ(d["start_list"].size(), d["starts"].get<std::size_t>()) << who;
  std::int64_t episodes = 0;
  std::map<std::string, int> counted;
  for (const auto& s : d["start_list"]) {
    EXPECT_TRUE(names.count(s["result"])) << who << ": " << s.dump();
    episodes += s["episodes"].get<std::int64_t>();
    ++counted[s["result"]];
  }
  EXPECT_EQ(episodes, r.episodes) << who;
  EXPECT_EQ(json(counted), d["results"]) << who;
  EXPECT_TRUE(d["early_return"].is_null()) << who;
  EXPECT_EQ(r.grad_evals, r.episodes) << who << ": L-BFGS asks for the gradient at every point";
}

void check_descents(const std::string& who, const StoredRun& r, bool single) {
  const json& d = r.diagnostics["optimizer"];
  const json& list = d["descent_list"];
  ASSERT_EQ(d["descent_list_truncated"], 0) << who;
  ASSERT_EQ(list.size(), d["descents"].get<std::size_t>()) << who;
  std::int64_t steps = 0;
  int by_reason = 0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    steps += list[i]["steps"].get<std::int64_t>();
    EXPECT_GT(list[i]["steps"].get<int>(), 0) << who;
    if (i + 1 < list.size()) {
      EXPECT_NE(list[i]["stop"], "budget") << who << " descent " << i;
    }
  }
  for (const auto& [reason, n] : d["stops"].items()) by_reason += n.get<int>();
  EXPECT_EQ(by_reason, static_cast<int>(list.size())) << who;
  EXPECT_EQ(steps, r.episodes) << who;
  EXPECT_EQ(r.grad_evals, r.episodes) << who;
  if (single) {
    EXPECT_EQ(list, json::parse(R"([{"steps": )" + std::to_string(r.budget) + R"(, "stop": "budget"}])")) << who;
  }
}

TEST_F(DiagnosticsCli, StoredDiagnosticsAgreeWithTheEvalsAndARerunGivesTheSameJson) {
  // cmaes gets a budget long enough for IPOP restarts on branin (2-D, population 6)
  const std::string grids[] = {
      "--env branin --optimizer bo,boleap,nlopt-lbfgs,gd,rand-descents,random --seeds 2 --budget 150",
      "--env branin --optimizer cmaes --seeds 2 --budget 1000"};
  for (const auto& grid : grids) {
    const auto a = harness(grid + " --quiet --jobs 1 --db " + db("a.sqlite"));
    ASSERT_EQ(a.code, 0) << a.err;
    const auto b = harness(grid + " --quiet --jobs 2 --db " + db("b.sqlite"));
    ASSERT_EQ(b.code, 0) << b.err;
  }
  const auto runs = read_runs(db("a.sqlite"));
  ASSERT_EQ(runs.size(), 14u);
  const int dim = 2;
  for (const auto& [id, r] : runs) {
    const auto& [env, optimizer, seed] = id;
    const std::string who = optimizer + " seed " + std::to_string(seed);
    ASSERT_EQ(r.status, "done") << who;
    ASSERT_TRUE(r.diagnostics.is_object()) << who << ": " << r.diagnostics_text;
    ASSERT_TRUE(r.diagnostics["optimizer"].is_object() && r.diagnostics["objective"].is_object()) << who;
    EXPECT_LT(r.diagnostics_text.size(), 8192u) << who;
    check_objective_side(who, r);
    if (optimizer == "cmaes") check_cmaes(who, r, dim);
    if (optimizer == "bo") check_bo(who, r, dim);
    if (optimizer == "boleap") check_boleap(who, r, dim);
    if (optimizer == "nlopt-lbfgs") check_nlopt(who, r);
    if (optimizer == "gd") check_descents(who, r, true);
    if (optimizer == "rand-descents") check_descents(who, r, false);
    if (optimizer == "random") {
      EXPECT_EQ(r.diagnostics["optimizer"], json::object()) << who;
    }
  }

  // identical reruns (other --jobs, other order) give identical JSON, byte for byte
  const auto again = read_runs(db("b.sqlite"));
  ASSERT_EQ(again.size(), runs.size());
  for (const auto& [id, r] : runs) {
    ASSERT_TRUE(again.count(id));
    EXPECT_EQ(again.at(id).diagnostics_text, r.diagnostics_text) << std::get<1>(id) << " seed " << std::get<2>(id);
  }
}

// one line on stderr, exit 2, the file's bytes unchanged
void expect_refused(const Result& r, const std::string& phrase) {
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(phrase), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(DiagnosticsCli, ANewerOrForeignDatabaseIsRefusedWithExitTwoAndLeftAlone) {
  const std::string grid = "--env branin --optimizer random --seeds 1 --budget 3 --quiet --db ";
  const std::string newer = db("newer.sqlite");
  ASSERT_EQ(harness(grid + newer).code, 0);
  {
    sqlite3* h = nullptr;
    ASSERT_EQ(sqlite3_open(newer.c_str(), &h), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(h, "UPDATE meta SET value='99' WHERE key='schema_version'", nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(h);
  }
  const std::string newer_bytes = read_file(newer);
  expect_refused(harness(grid + newer), "newer than this harness");
  EXPECT_EQ(read_file(newer), newer_bytes);

  const std::string foreign = db("foreign.sqlite");
  {
    sqlite3* h = nullptr;
    ASSERT_EQ(sqlite3_open(foreign.c_str(), &h), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(h, "CREATE TABLE runs(id INTEGER PRIMARY KEY, name TEXT); INSERT INTO runs VALUES (1, 'x')",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(h);
  }
  const std::string foreign_bytes = read_file(foreign);
  expect_refused(harness(grid + foreign), "is not a harness database");
  EXPECT_EQ(read_file(foreign), foreign_bytes);
}

}  // namespace
}  // namespace dsb
