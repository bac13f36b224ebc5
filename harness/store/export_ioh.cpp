// `harness export --format ioh`: IOHprofiler's analyzer format for IOHanalyzer.
//
// What it writes follows IOHexperimenter's Analyzer logger as documented by IOHprofiler (format
// "v2", the logger's default):
//
//   OUT/<algorithm>/IOHprofiler_f<fid>_<function>.json            one meta file per function
//   OUT/<algorithm>/data_f<fid>_<function>/IOHprofiler_f<fid>_DIM<d>.dat
//
// The JSON holds version, suite, function_id, function_name, maximization (false: every loss is
// minimized), algorithm {name, info}, experiment_attributes and run_attributes (both empty),
// attributes (the .dat columns) and scenarios[], one per dimension (here always one), each with
// its dimension, the .dat path relative to the JSON's folder and runs[]: {instance, evals,
// best {evals, y, x}} in the order of the .dat's blocks. The .dat is space-separated; each run is
// one block that starts with the header line "evaluations raw_y", then one row per improvement of
// the best-so-far loss (IOH's default trigger, on_improvement): "<evaluations> <raw_y>".
// One folder per algorithm, since one meta file names one algorithm.
//
// Mapping (docs/reports.md "IOHanalyzer export"):
// - function = env: function_name the env name, function_id its 1-based position in the sorted
//   function names of the exported database (ids are stable for one database, not across
//   databases: the name is the key). An env name stored with more than one env config hash is one
//   function per hash, named "<env>-<first 8 hex digits of the hash>".
// - dimension = the env's dim: the length of the run's best_x (what it searched), or, without one,
//   the registry's EnvInfo::dim.
// - algorithm = optimizer. Runs of one optimizer with different budgets or optimizer config hashes
//   on the same env are separate algorithms: an optimizer that has more than one budget on some
//   env is named "<optimizer>-b<budget>" on every env, one with more than one config hash on some
//   env "<optimizer>-<first 8 hex digits of the hash>" (both suffixes when both vary), so one
//   name means one (optimizer, budget, config) on every function.
// - instance = seed index; evals = the run's episodes; evaluations = episode + 1; raw_y = loss.
// - Only runs with status 'done'. Failed episodes (NULL loss) and non-finite losses write no row:
//   they still count as evaluations (the counter is episode + 1, and the run's evals is every
//   episode), they never improve the best. A run without a single finite loss is left out (no
//   block, no run entry) and counted in the summary.
// - Numbers: .dat values are written in the shortest form that reads back as the same double
//   (fmt's "{}"); the JSON's numbers likewise (nlohmann::json).
#include "harness/store/export_ioh.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "envs/registry.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/tables.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

std::string short_hash(const std::string& hash) { return hash.substr(0, 8); }

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
  out << text;
  out.close();
  if (!out) throw std::runtime_error("writing '" + path.string() + "' failed");
}

std::string join(const std::set<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ",") + i;
  return s;
}

}  // namespace

std::string ioh_file_safe(const std::string& name) {
  std::string s = name;
  for (char& c : s) {
    const bool ok =
        (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  return s;
}

std::vector<IohRun> read_ioh_runs(Database& db, bool include_stale, std::int64_t* stale_left_out) {
  std::vector<IohRun> runs;
  std::map<std::int64_t, std::size_t> index;
  if (stale_left_out) *stale_left_out = 0;
  {
    const int schema = check_schema(db);
    Statement q(db.handle(),
                std::string(R"sql(
      SELECT run_id, env, optimizer, seed, budget, env_config_hash, opt_config_hash, episodes, best_x,
             )sql") +
                    read_column(runs_table(), "harness_version", schema) + ", " +
                    read_column(runs_table(), "results_versions", schema) + R"sql(
      FROM runs WHERE status = 'done'
      ORDER BY env, optimizer, budget, opt_config_hash, env_config_hash, seed, run_id)sql");
    while (q.step()) {
      // a stale run (other results versions: harness/core/results_versions.hpp) only when asked for
      const ResultsVersions versions = stored_results_versions(q.column_text(10));
      const bool stale = !stale_reason(q.column_text(1), q.column_text(2), versions).empty();
      if (stale && !include_stale) {
        if (stale_left_out) ++*stale_left_out;
        continue;
      }
      IohRun r;
      r.stale = stale;
      r.results_versions = versions.text();
      r.run_id = q.column_int(0);
      r.env = q.column_text(1);
      r.optimizer = q.column_text(2);
      r.seed = static_cast<int>(q.column_int(3));
      r.budget = q.column_int(4);
      r.env_hash = q.column_text(5);
      r.opt_hash = q.column_text(6);
      r.episodes = q.column_int(7);
      if (!q.column_is_null(8)) {
        r.best_x = nlohmann::json::parse(q.column_text(8), nullptr, false);
        r.has_best_x = r.best_x.is_array() && !r.best_x.empty();
        if (!r.has_best_x) r.best_x = nlohmann::json::array();
      } else {
        r.best_x = nlohmann::json::array();
      }
      r.version = q.column_text(9);
      index[r.run_id] = runs.size();
      runs.push_back(std::move(r));
    }
  }
  Statement q(db.handle(), R"sql(
    SELECT e.run_id, e.episode, e.loss FROM evals e JOIN runs r USING(run_id)
    WHERE r.status = 'done' ORDER BY e.run_id, e.episode)sql");
  std::int64_t current = -1;
  double best = 0.0;
  IohRun* run = nullptr;
  while (q.step()) {
    const std::int64_t id = q.column_int(0);
    if (id != current) {
      current = id;
      const auto at = index.find(id);
      run = at == index.end() ? nullptr : &runs[at->second];  // nullptr: a stale run left out
    }
    if (!run) continue;
    const std::int64_t episode = q.column_int(1);
    run->episodes = std::max(run->episodes, episode + 1);
    if (q.column_is_null(2)) continue;  // failed episode: no row
    const double loss = q.column_double(2);
    if (!std::isfinite(loss)) continue;
    if (run->rows.empty() || loss < best) {
      best = loss;
      run->rows.emplace_back(episode + 1, loss);
    }
  }
  return runs;
}

IohExportSummary write_ioh_export(const std::vector<IohRun>& all, const fs::path& out_dir) {
  IohExportSummary summary;
  std::vector<IohRun> runs;
  for (const auto& r : all) {
    if (r.rows.empty())
      ++summary.runs_left_out;
    else
      runs.push_back(r);
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) throw std::runtime_error("cannot create folder '" + out_dir.string() + "'");

  // functions: env names, split by env config hash where one name has several
  std::map<std::string, std::set<std::string>> env_hashes;
  for (const auto& r : runs) env_hashes[r.env].insert(r.env_hash);
  auto function_name = [&](const IohRun& r) {
    return env_hashes[r.env].size() > 1 ? r.env + "-" + short_hash(r.env_hash) : r.env;
  };
  std::map<std::string, int> function_id;
  for (const auto& r : runs) function_id[function_name(r)] = 0;
  int next_id = 1;
  for (auto& [name, id] : function_id) id = next_id++;

  // algorithms: optimizer, suffixed where one env has it with several budgets or configs
  std::map<std::pair<std::string, std::string>, std::set<std::int64_t>> budgets;  // (optimizer, env)
  std::map<std::pair<std::string, std::string>, std::set<std::string>> configs;
  for (const auto& r : runs) {
    budgets[{r.optimizer, function_name(r)}].insert(r.budget);
    configs[{r.optimizer, function_name(r)}].insert(r.opt_hash);
  }
  std::set<std::string> by_budget, by_config;
  for (const auto& [key, b] : budgets)
    if (b.size() > 1) by_budget.insert(key.first);
  for (const auto& [key, c] : configs)
    if (c.size() > 1) by_config.insert(key.first);
  auto algorithm_name = [&](const IohRun& r) {
    std::string name = r.optimizer;
    if (by_budget.count(r.optimizer)) name += fmt::format("-b{}", r.budget);
    if (by_config.count(r.optimizer)) name += fmt::format("-{}", short_hash(r.opt_hash));
    // a stale run (--include-stale) is its own algorithm, named by its versions: never mixed with
    // the current runs or another version's
    if (r.stale) {
      const ResultsVersions v = stored_results_versions(r.results_versions);
      name += r.results_versions.empty() ? std::string("-stale-unversioned")
                                         : fmt::format("-stale-e{}o{}r{}", v.env, v.optimizer, v.run);
    }
    return name;
  };

  // groups: (algorithm, function) -> runs, in (seed, run_id) order
  std::map<std::pair<std::string, std::string>, std::vector<const IohRun*>> groups;
  for (const auto& r : runs) groups[{algorithm_name(r), function_name(r)}].push_back(&r);
  std::map<std::string, std::string> folder_of;  // file-safe folder -> algorithm
  for (const auto& [key, members] : groups) {
    const auto [it, fresh] = folder_of.emplace(ioh_file_safe(key.first), key.first);
    if (!fresh && it->second != key.first)
      throw std::runtime_error("algorithms '" + it->second + "' and '" + key.first + "' map to one folder name");
  }

  std::set<std::string> algorithms;
  for (auto& [key, members] : groups) {
    const auto& [algorithm, function] = key;
    const IohRun& first = *members.front();
    std::set<std::string> versions;
    int dim = 0;
    for (const IohRun* r : members) {
      if (r->budget != first.budget || r->opt_hash != first.opt_hash)  // only on a short-hash collision
        throw std::runtime_error("algorithm '" + algorithm + "' on '" + function + "' mixes budgets or configs");
      if (!r->version.empty()) versions.insert(r->version);
      if (!r->has_best_x) continue;
      const int d = static_cast<int>(r->best_x.size());
      if (dim != 0 && d != dim)
        throw std::runtime_error("env '" + function + "': runs of dimensions " + std::to_string(dim) + " and " +
                                 std::to_string(d));
      dim = d;
    }
    if (dim == 0) {
      try {
        dim = shared_env(first.env)->info().dim;
      } catch (const std::exception& e) {
        throw std::runtime_error("cannot tell the dimension of env '" + first.env + "' (no best_x stored, and " +
                                 e.what() + ")");
      }
    }

    const int fid = function_id.at(function);
    const std::string fname = ioh_file_safe(function);
    const fs::path folder = out_dir / ioh_file_safe(algorithm);
    const std::string data_dir = fmt::format("data_f{}_{}", fid, fname);
    const std::string dat_name = fmt::format("IOHprofiler_f{}_DIM{}.dat", fid, dim);
    fs::create_directories(folder / data_dir, ec);
    if (ec) throw std::runtime_error("cannot create '" + (folder / data_dir).string() + "': " + ec.message());

    std::string dat;
    nlohmann::ordered_json run_list = nlohmann::ordered_json::array();
    for (const IohRun* r : members) {
      dat += "evaluations raw_y\n";
      for (const auto& [evals, y] : r->rows) dat += fmt::format("{} {}\n", evals, y);
      summary.rows += static_cast<std::int64_t>(r->rows.size());
      const auto& [best_evals, best_y] = r->rows.back();
      nlohmann::ordered_json run;
      run["instance"] = r->seed;
      run["evals"] = r->episodes;
      run["best"] = {{"evals", best_evals}, {"y", best_y}, {"x", r->best_x}};
      run_list.push_back(std::move(run));
      ++summary.runs;
    }
    write_text(folder / data_dir / dat_name, dat);

    nlohmann::ordered_json meta;
    meta["version"] = versions.empty() ? std::string("unknown") : join(versions);
    meta["suite"] = "diffsim-bench";
    meta["function_id"] = fid;
    meta["function_name"] = function;
    meta["maximization"] = false;
    meta["algorithm"] = {{"name", algorithm},
                         {"info",
                          fmt::format("diffsim-bench optimizer {}, budget {}, optimizer config {}, env config {}",
                                      first.optimizer, first.budget, first.opt_hash, first.env_hash)}};
    meta["experiment_attributes"] = nlohmann::ordered_json::array();
    meta["run_attributes"] = nlohmann::ordered_json::array();
    meta["attributes"] = {"evaluations", "raw_y"};
    nlohmann::ordered_json scenario;
    scenario["dimension"] = dim;
    scenario["path"] = data_dir + "/" + dat_name;
    scenario["runs"] = std::move(run_list);
    meta["scenarios"] = nlohmann::ordered_json::array({std::move(scenario)});
    write_text(folder / fmt::format("IOHprofiler_f{}_{}.json", fid, fname), meta.dump(1) + "\n");
    algorithms.insert(algorithm);
  }
  summary.algorithms = static_cast<int>(algorithms.size());
  summary.functions = static_cast<int>(function_id.size());
  return summary;
}

}  // namespace dsb
