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

namespace dsb {

class Database;

inline constexpr const char* kResultTableHeader =
    "env,optimizer,seed,budget,env_config_hash,opt_config_hash,episode,loss";

struct ResultRow {
  std::string env, optimizer;
  int seed = 0;
  std::int64_t budget = 0;
  std::string env_config_hash, opt_config_hash;
  std::int64_t episode = 0;
  std::string loss;  // "%.17g", or "nan" for a failed episode

  auto key() const { return std::tie(env, optimizer, seed, budget, episode); }
  std::string csv() const;
};

// a baseline that is not a result table: the message names the file, line and problem
struct BaselineError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// every episode of every 'done' run, sorted by (env, optimizer, seed, budget, episode)
std::vector<ResultRow> read_result_table(Database& db);
// the same of a database file, read-only; UsageError "--db: ..." when it is missing or unreadable
std::vector<ResultRow> result_table_of_file(const std::string& db_path);
std::vector<ResultRow> read_result_csv(const std::string& path);  // throws BaselineError
void write_result_csv(const std::vector<ResultRow>& rows, std::ostream& out);

struct TableDiff {
  std::vector<std::pair<ResultRow, ResultRow>> changed;  // (baseline, current)
  std::vector<ResultRow> missing;  // in the baseline, not in the database
  std::vector<ResultRow> added;    // in the database, not in the baseline
  std::size_t equal = 0;
  bool empty() const { return changed.empty() && missing.empty() && added.empty(); }
};

TableDiff compare_tables(const std::vector<ResultRow>& baseline, const std::vector<ResultRow>& current);

// human-readable diff, at most `limit` rows of each kind
void print_diff(const TableDiff& diff, std::ostream& out, std::size_t limit = 20);

}  // namespace dsb
