#pragma once
// Result tables for regression CI: one row per episode of every 'done' run, losses printed with
// 17 significant digits (a double round-trips exactly), compared row by row with a baseline CSV.
#include <cstdint>
#include <iosfwd>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "harness/core/results_versions.hpp"

namespace dsb {

class Database;

// A row carries the results versions of its run (harness/core/results_versions.hpp): a result that
// changes while its versions do not is a silent change, which `check` names.
inline constexpr const char* kResultTableHeader =
    "env,optimizer,seed,budget,env_config_hash,opt_config_hash,env_version,optimizer_version,run_version,episode,loss";
// the header of an export with --include-stale: one more column, stale (1 for a stale run's rows)
inline constexpr const char* kResultTableStaleColumn = "stale";

struct ResultRow {
  std::string env, optimizer;
  int seed = 0;
  std::int64_t budget = 0;
  std::string env_config_hash, opt_config_hash;
  ResultsVersions versions;
  std::int64_t episode = 0;
  std::string loss;    // "%.17g", or "nan" for a failed episode
  bool stale = false;  // versions not this binary's (rows of such runs are only read with include_stale)

  auto key() const { return std::tie(env, optimizer, seed, budget, episode); }
  std::string csv() const;  // the columns of kResultTableHeader (not `stale`)
};

// the done runs a result table left out because they are stale, by env, optimizer and reason
struct LeftOutRuns {
  std::string env, optimizer, reason;
  std::int64_t runs = 0;
};

struct ResultTable {
  std::vector<ResultRow> rows;
  std::vector<LeftOutRuns> stale;  // left out (or, with include_stale, included and marked)
  std::int64_t stale_runs() const;
};

// a baseline that is not a result table: the message names the file, line and problem
struct BaselineError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// every episode of every 'done' run whose results versions are this binary's, sorted by (env,
// optimizer, seed, budget, episode); stale runs are counted in `stale`, and their rows are in
// `rows` too (marked) only with include_stale. A database of schema 4 or older has no versions:
// all its runs are stale.
ResultTable read_result_table(Database& db, bool include_stale = false);
// the same of a database file, read-only; UsageError "--db: ..." when it is missing or unreadable
ResultTable result_table_of_file(const std::string& db_path, bool include_stale = false);
std::vector<ResultRow> read_result_csv(const std::string& path);  // throws BaselineError
// the rows as CSV; with_stale adds the `stale` column
void write_result_csv(const std::vector<ResultRow>& rows, std::ostream& out, bool with_stale = false);
// one line saying how many done runs were left out as stale and why, e.g. "left out 3 stale runs
// (made by other results versions; --include-stale shows them): plb-pinch / gd: 3: env plb-pinch
// version 1, this binary's 2"; "" when none
std::string stale_note(const ResultTable& table, bool included);

struct TableDiff {
  std::vector<std::pair<ResultRow, ResultRow>> changed;  // (baseline, current)
  std::vector<ResultRow> missing;                        // in the baseline, not in the database
  std::vector<ResultRow> added;                          // in the database, not in the baseline
  std::size_t equal = 0;
  bool empty() const { return changed.empty() && missing.empty() && added.empty(); }
};

TableDiff compare_tables(const std::vector<ResultRow>& baseline, const std::vector<ResultRow>& current);

// human-readable diff, at most `limit` rows of each kind
void print_diff(const TableDiff& diff, std::ostream& out, std::size_t limit = 20);

// What the diff means per env and optimizer, one line each: a pair whose rows changed while its
// results versions did not is a silent change ("... changed while its results versions did not:
// bump its results version ..."); a pair whose versions changed needs the baseline regenerated.
// `regenerate` is the command that regenerates the baseline. Returns the number of lines.
std::size_t print_verdicts(const TableDiff& diff, std::ostream& out, const std::string& regenerate);

}  // namespace dsb
