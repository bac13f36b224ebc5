#pragma once
// `harness export --format ioh`: the database's 'done' runs in IOHprofiler's analyzer format (the
// JSON-meta "v2" layout that IOHexperimenter's Analyzer logger writes), for IOHanalyzer. Format,
// mapping and rules: export_ioh.cpp's header comment and docs/reports.md ("IOHanalyzer export").
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/results_versions.hpp"

namespace dsb {

class Database;

struct IohExportSummary {
  int algorithms = 0;     // folders written, one per algorithm
  int functions = 0;      // distinct functions (envs)
  int runs = 0;           // runs written
  int runs_left_out = 0;  // 'done' runs without a single finite loss
  std::int64_t rows = 0;  // .dat data rows (improvements)
};

// One 'done' run as exported: its key, episodes, best_x and the improvements of its best loss.
struct IohRun {
  std::int64_t run_id = 0;
  std::string env, optimizer;
  int seed = 0;
  std::int64_t budget = 0;
  std::string env_hash, opt_hash;
  std::int64_t episodes = 0;
  bool has_best_x = false;
  nlohmann::json best_x;                              // array, normalized units ([] when none)
  std::string results_versions;                       // "env E, optimizer O, run R" ("" before versions)
  bool stale = false;                                 // versions not this binary's
  std::string version;                                // harness_version
  std::vector<std::pair<std::int64_t, double>> rows;  // improvements: (episode + 1, loss)
};

// Every 'done' run of `db`, ordered by (env, optimizer, budget, configs, seed). Reads only;
// throws StoreError on a database error.
// the done runs whose results versions are this binary's (all of them with include_stale: the
// stale ones marked); stale_left_out (may be null) counts those left out
std::vector<IohRun> read_ioh_runs(Database& db, bool include_stale = false, std::int64_t* stale_left_out = nullptr);

// Writes the IOH folder tree of `runs` under `out_dir` (created if missing; the caller checks it
// is new or empty). Throws std::runtime_error naming a file or folder that cannot be written.
IohExportSummary write_ioh_export(const std::vector<IohRun>& runs, const std::filesystem::path& out_dir);

// Names used in the export (exposed for tests and documentation):
// a name made safe for a file name: characters other than [A-Za-z0-9._-] become '_'
std::string ioh_file_safe(const std::string& name);

}  // namespace dsb
