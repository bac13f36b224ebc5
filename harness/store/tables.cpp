#include "harness/store/tables.hpp"

#include <stdexcept>

namespace dsb {

const Table& meta_table() {
  static const Table t{"meta",
                       {
                           {"key", "TEXT PRIMARY KEY", nullptr, ""},
                           {"value", "TEXT NOT NULL", nullptr, ""},
                       },
                       "",
                       false};
  return t;
}

const Table& configs_table() {
  static const Table t{"configs",
                       {
                           {"hash", "TEXT PRIMARY KEY", nullptr, ""},
                           {"kind", "TEXT NOT NULL", nullptr, "'env' or 'optimizer'"},
                           {"json", "TEXT NOT NULL", nullptr, "resolved config, canonical JSON"},
                       },
                       "",
                       false};
  return t;
}

// One row per run; the UNIQUE key is the run key (harness/core/run_key.hpp). Columns added by
// migrations come last, so a migrated file and a new one have the same column order.
const Table& runs_table() {
  static const Table t{
      "runs",
      {
          {"run_id", "INTEGER PRIMARY KEY", nullptr, ""},
          {"env", "TEXT NOT NULL", nullptr, "", 1, 1},
          {"optimizer", "TEXT NOT NULL", nullptr, "", 1, 1},
          {"seed", "INTEGER NOT NULL", nullptr, "seed index 0..seeds-1", 1, 1},
          {"budget", "INTEGER NOT NULL", nullptr, "episodes", 1, 1},
          {"env_config_hash", "TEXT NOT NULL REFERENCES configs(hash)", nullptr, "", 1, 1},
          {"opt_config_hash", "TEXT NOT NULL REFERENCES configs(hash)", nullptr, "", 1, 1},
          {"rng_seed", "TEXT NOT NULL", nullptr, "per-run 64-bit seed, hex"},
          {"status", "TEXT NOT NULL CHECK(status IN ('done', 'failed', 'running'))", nullptr, ""},
          {"episodes", "INTEGER NOT NULL", "0", ""},
          {"failed_episodes", "INTEGER NOT NULL", "0", ""},
          {"best_loss", "REAL", nullptr, "NULL when no episode succeeded"},
          {"best_x", "TEXT", nullptr, "JSON array, normalized units"},
          {"wall_s", "REAL", nullptr, ""},
          {"error", "TEXT", nullptr, ""},
          {"started_at", "TEXT", nullptr, ""},
          {"finished_at", "TEXT", nullptr, ""},
          {"harness_version", "TEXT NOT NULL", "''", "part of the run key (version 3)", 1, 3},
          {"git_sha", "TEXT", nullptr, ""},
          {"host", "TEXT", nullptr, ""},
          {"diagnostics", "TEXT", nullptr, "JSON {\"optimizer\": {...}, \"objective\": {...}} (version 2)", 2},
          {"seed_free_episodes", "INTEGER", nullptr, "episodes before the optimizer's first draw (NULL: unknown)", 4},
          {"seed_free_calls", "INTEGER", nullptr, "the journal entries that produced them", 4},
          {"shared_episodes", "INTEGER NOT NULL", "0", "episodes replayed from another seed's run", 4},
          {"shared_from_seed", "INTEGER", nullptr, "that run's seed", 4},
          {"results_versions", "TEXT NOT NULL", "''", "part of the run key (version 5): 'env E, optimizer O, run R'", 5,
           5},
          {"cpu_s", "REAL", nullptr,
           "CPU seconds of the run's worker thread over its sessions; NULL: unknown (--threads > 1, ext:, "
           "older sessions) (version 6)",
           6},
      },
      "",
      false};
  return t;
}

// One row per committed episode of a run.
const Table& evals_table() {
  static const Table t{
      "evals",
      {
          {"run_id", "INTEGER NOT NULL REFERENCES runs(run_id)", nullptr, ""},
          {"episode", "INTEGER NOT NULL", nullptr, "0-based"},
          {"loss", "REAL", nullptr, "NULL for a failed episode (simulation blew up)"},
          {"best_loss", "REAL", nullptr, "best finite loss so far"},
          {"used_grad", "INTEGER NOT NULL", nullptr, ""},
          {"wall_s", "REAL NOT NULL", nullptr, ""},
          {"failed", "INTEGER NOT NULL", "0", ""},
          {"metric", "REAL", nullptr, "optional second per-episode metric, NULL when none (version 2)", 2},
      },
      "run_id, episode",
      true};
  return t;
}

namespace {

// a journal of objective calls (replay and prefix have the same rows): one row per call (kind:
// harness/core/replay.hpp), the digest of the call's input and what the call returned (payload:
// doubles, native byte order)
Table journal_table(const char* name, const char* seq_comment, int since) {
  return {name,
          {
              {"run_id", "INTEGER NOT NULL REFERENCES runs(run_id)", nullptr, ""},
              {"seq", "INTEGER NOT NULL", nullptr, seq_comment},
              {"kind", "INTEGER NOT NULL", nullptr, ""},
              {"input_hash", "INTEGER NOT NULL", nullptr, ""},
              {"payload", "BLOB NOT NULL", nullptr, ""},
          },
          "run_id, seq",
          true,
          since};
}

}  // namespace

// What a run that is not done yet needs to be resumed by replay (version 3). A run's rows are
// deleted when it ends.
const Table& replay_table() {
  static const Table t = journal_table("replay", "0-based call index within the run", 3);
  return t;
}

// The journal of a done run's seed-free episodes (version 4): what a run of another seed replays
// instead of simulating them (harness/store/store.hpp).
const Table& prefix_table() {
  static const Table t = journal_table("prefix", "", 4);
  return t;
}

const std::vector<const Table*>& all_tables() {
  static const std::vector<const Table*> tables = {&meta_table(),  &configs_table(), &runs_table(),
                                                   &evals_table(), &replay_table(),  &prefix_table()};
  return tables;
}

std::vector<const Column*> columns_at(const Table& table, int version) {
  std::vector<const Column*> cols;
  for (const Column& c : table.columns)
    if (c.since <= version) cols.push_back(&c);
  return cols;
}

std::vector<std::string> unique_key_columns(const Table& table, int version) {
  std::vector<std::string> key;
  for (const Column* c : columns_at(table, version))
    if (c->key_since > 0 && c->key_since <= version) key.push_back(c->name);
  return key;
}

std::string unique_key(const Table& table, int version) {
  std::string key;
  for (const auto& c : unique_key_columns(table, version)) key += (key.empty() ? "" : ", ") + c;
  return key;
}

std::string default_value(const Column& column) { return column.default_sql ? column.default_sql : "NULL"; }

std::string create_table_sql(const Table& table, int version, const std::string& name) {
  // the table constraints after the columns: the UNIQUE key, then a composite primary key
  std::vector<std::string> constraints;
  if (const std::string key = unique_key(table, version); !key.empty()) constraints.push_back("UNIQUE(" + key + ")");
  if (*table.primary_key) constraints.push_back("PRIMARY KEY(" + std::string(table.primary_key) + ")");
  const std::string close = std::string(")") + (table.without_rowid ? " WITHOUT ROWID" : "") + ";";
  std::vector<std::string> lines;
  const auto cols = columns_at(table, version);
  for (std::size_t i = 0; i < cols.size(); ++i) {
    const Column& c = *cols[i];
    std::string line = "  " + std::string(c.name) + " " + c.type;
    if (c.default_sql) line += " DEFAULT " + std::string(c.default_sql);
    line += (i + 1 == cols.size() && constraints.empty()) ? close : ",";
    // the comment starts at column 32, at least two spaces after the definition
    if (*c.comment) line += std::string(line.size() + 2 < 32 ? 32 - line.size() : 2, ' ') + "-- " + c.comment;
    lines.push_back(line);
  }
  for (std::size_t i = 0; i < constraints.size(); ++i)
    lines.push_back("  " + constraints[i] + (i + 1 == constraints.size() ? close : ","));
  std::string sql = "CREATE TABLE " + name + "(\n";
  for (const auto& line : lines) sql += line + "\n";
  return sql;
}

std::string column_names(const Table& table, int version, const std::string& skip) {
  std::string names;
  for (const Column* c : columns_at(table, version))
    if (c->name != skip) names += (names.empty() ? "" : ", ") + std::string(c->name);
  return names;
}

std::string placeholders(int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += i ? ", ?" : "?";
  return s;
}

namespace {

const Column& find_column(const Table& table, const std::string& column) {
  for (const Column& c : table.columns)
    if (c.name == column) return c;
  throw std::logic_error("table " + std::string(table.name) + " has no column " + column);
}

}  // namespace

std::string read_column(const Table& table, const std::string& column, int version) {
  const Column& c = find_column(table, column);
  const std::string fallback = default_value(c);
  if (c.since > version) return fallback;
  // a run key column is never NULL: files from before it joined the key may hold NULL there
  if (c.key_since > 0 && c.default_sql) return "COALESCE(" + column + ", " + fallback + ")";
  return column;
}

std::string read_columns(const Table& table, int version, const std::string& skip) {
  std::string sql;
  for (const Column& c : table.columns)
    if (c.name != skip) sql += (sql.empty() ? "" : ", ") + read_column(table, c.name, version);
  return sql;
}

int column_index(const Table& table, const std::string& column, const std::string& skip) {
  int i = 0;
  for (const Column& c : table.columns) {
    if (c.name == skip) continue;
    if (c.name == column) return i;
    ++i;
  }
  throw std::logic_error("table " + std::string(table.name) + " has no column " + column);
}

}  // namespace dsb
