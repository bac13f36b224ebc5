#include "harness/store/schema.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <vector>

namespace dsb {

namespace {

// runs' columns of version 4, in the order a migration adds them
const std::string kSharingColumns =
    R"sql(  seed_free_episodes INTEGER,   -- episodes before the optimizer's first draw (NULL: unknown)
  seed_free_calls INTEGER,      -- the journal entries that produced them
  shared_episodes INTEGER NOT NULL DEFAULT 0,  -- episodes replayed from another seed's run
  shared_from_seed INTEGER,     -- that run's seed
)sql";

// The runs table of a schema version under a name (the migration to version 3 builds it beside
// the old one). Columns added by migrations come last, so a migrated file and a new one have the
// same column order.
std::string runs_table_sql(const std::string& name, int version) {
  const std::string versions_column = version >= 5
      ? "  results_versions TEXT NOT NULL DEFAULT '',  -- part of the run key (version 5): 'env E, optimizer O, run R'\n"
      : "";
  const std::string key = version >= 5 ? ", results_versions" : "";
  return "CREATE TABLE " + name + R"sql((
  run_id INTEGER PRIMARY KEY,
  env TEXT NOT NULL,
  optimizer TEXT NOT NULL,
  seed INTEGER NOT NULL,        -- seed index 0..seeds-1
  budget INTEGER NOT NULL,      -- episodes
  env_config_hash TEXT NOT NULL REFERENCES configs(hash),
  opt_config_hash TEXT NOT NULL REFERENCES configs(hash),
  rng_seed TEXT NOT NULL,       -- per-run 64-bit seed, hex
  status TEXT NOT NULL CHECK(status IN ('done', 'failed', 'running')),
  episodes INTEGER NOT NULL DEFAULT 0,
  failed_episodes INTEGER NOT NULL DEFAULT 0,
  best_loss REAL,               -- NULL when no episode succeeded
  best_x TEXT,                  -- JSON array, normalized units
  wall_s REAL,
  error TEXT,
  started_at TEXT,
  finished_at TEXT,
  harness_version TEXT NOT NULL DEFAULT '',  -- part of the run key (version 3)
  git_sha TEXT,
  host TEXT,
  diagnostics TEXT,             -- JSON {"optimizer": {...}, "objective": {...}} (version 2)
)sql" +
      (version >= 4 ? kSharingColumns : std::string()) + versions_column +
      "  UNIQUE(env, optimizer, seed, budget, env_config_hash, opt_config_hash, harness_version" + key + "));\n";
}

// The journal of a done run's seed-free episodes (version 4): what a run of another seed replays
// instead of simulating them (harness/store/store.hpp). Rows as in `replay`.
const char* kPrefixTable = R"sql(
CREATE TABLE prefix(
  run_id INTEGER NOT NULL REFERENCES runs(run_id),
  seq INTEGER NOT NULL,
  kind INTEGER NOT NULL,
  input_hash INTEGER NOT NULL,
  payload BLOB NOT NULL,
  PRIMARY KEY(run_id, seq)) WITHOUT ROWID;
)sql";

// What a run that is not done yet needs to be resumed by replay (version 3): one row per
// objective call (kind: harness/core/replay.hpp), the digest of the call's input and what the call
// returned (payload: doubles, native byte order). A run's rows are deleted when it ends.
const char* kReplayTable = R"sql(
CREATE TABLE replay(
  run_id INTEGER NOT NULL REFERENCES runs(run_id),
  seq INTEGER NOT NULL,         -- 0-based call index within the run
  kind INTEGER NOT NULL,
  input_hash INTEGER NOT NULL,
  payload BLOB NOT NULL,
  PRIMARY KEY(run_id, seq)) WITHOUT ROWID;
)sql";

// the newest schema, for a new file
std::string create_schema_sql() {
  return R"sql(
CREATE TABLE meta(
  key TEXT PRIMARY KEY,
  value TEXT NOT NULL);
CREATE TABLE configs(
  hash TEXT PRIMARY KEY,
  kind TEXT NOT NULL,           -- 'env' or 'optimizer'
  json TEXT NOT NULL);          -- resolved config, canonical JSON
)sql" +
      runs_table_sql("runs", kSchemaVersion) +
      R"sql(
CREATE TABLE evals(
  run_id INTEGER NOT NULL REFERENCES runs(run_id),
  episode INTEGER NOT NULL,     -- 0-based
  loss REAL,                    -- NULL for a failed episode (simulation blew up)
  best_loss REAL,               -- best finite loss so far
  used_grad INTEGER NOT NULL,
  wall_s REAL NOT NULL,
  failed INTEGER NOT NULL DEFAULT 0,
  metric REAL,                  -- optional second per-episode metric, NULL when none (version 2)
  PRIMARY KEY(run_id, episode)) WITHOUT ROWID;
)sql" +
      kReplayTable + kPrefixTable;
}

// One step of the chain: SQL that takes a database of version `from` to version from + 1.
struct Migration {
  int from;
  std::string sql;
};

std::vector<Migration> migrations() {
  // 2 -> 3: the run key gains harness_version. SQLite cannot change a UNIQUE constraint, so the
  // runs table is rebuilt beside the old one (run_ids kept, so evals still point at their runs;
  // prepare_schema migrates with foreign keys off), then the replay table is added.
  const std::string columns =
      "run_id, env, optimizer, seed, budget, env_config_hash, opt_config_hash, rng_seed, status, episodes, "
      "failed_episodes, best_loss, best_x, wall_s, error, started_at, finished_at, {version}, git_sha, host, "
      "diagnostics";
  auto with = [&](const std::string& version) {
    std::string c = columns;
    return c.replace(c.find("{version}"), 9, version);
  };
  const std::string v4_columns = ", seed_free_episodes, seed_free_calls, shared_episodes, shared_from_seed";
  return {
      {1,
       "ALTER TABLE runs ADD COLUMN diagnostics TEXT;"
       "ALTER TABLE evals ADD COLUMN metric REAL;"},
      {2,
       runs_table_sql("runs_v3", 3) + "INSERT INTO runs_v3(" + with("harness_version") + ") SELECT " +
           with("COALESCE(harness_version, '')") +
           " FROM runs;"
           "DROP TABLE runs;"
           "ALTER TABLE runs_v3 RENAME TO runs;" +
           kReplayTable},
      {3,
       "ALTER TABLE runs ADD COLUMN seed_free_episodes INTEGER;"
       "ALTER TABLE runs ADD COLUMN seed_free_calls INTEGER;"
       "ALTER TABLE runs ADD COLUMN shared_episodes INTEGER NOT NULL DEFAULT 0;"
       "ALTER TABLE runs ADD COLUMN shared_from_seed INTEGER;" +
           std::string(kPrefixTable)},
      // 4 -> 5: the run key gains results_versions ('' in every old row: made before versions, so
      // stale for every binary that has them); the table is rebuilt as for 3, run_ids kept
      {4,
       runs_table_sql("runs_v5", 5) + "INSERT INTO runs_v5(" + with("harness_version") + v4_columns + ") SELECT " +
           with("harness_version") + v4_columns +
           " FROM runs;"
           "DROP TABLE runs;"
           "ALTER TABLE runs_v5 RENAME TO runs;"},
  };
}

// The columns every table must have at a version (a file may have more).
std::map<std::string, std::vector<std::string>> required_columns(int version) {
  std::map<std::string, std::vector<std::string>> cols = {
      {"meta", {"key", "value"}},
      {"configs", {"hash", "kind", "json"}},
      {"runs", {"run_id",          "env",      "optimizer", "seed",       "budget",          "env_config_hash",
                "opt_config_hash", "rng_seed", "status",    "episodes",   "failed_episodes", "best_loss",
                "best_x",          "wall_s",   "error",     "started_at", "finished_at",     "harness_version",
                "git_sha",         "host"}},
      {"evals", {"run_id", "episode", "loss", "best_loss", "used_grad", "wall_s", "failed"}},
  };
  if (version >= 2) {
    cols["runs"].push_back("diagnostics");
    cols["evals"].push_back("metric");
  }
  if (version >= 3) cols["replay"] = {"run_id", "seq", "kind", "input_hash", "payload"};
  if (version >= 4) {
    for (const char* c : {"seed_free_episodes", "seed_free_calls", "shared_episodes", "shared_from_seed"})
      cols["runs"].push_back(c);
    cols["prefix"] = {"run_id", "seq", "kind", "input_hash", "payload"};
  }
  if (version >= 5) cols["runs"].push_back("results_versions");
  return cols;
}

std::set<std::string> table_names(Database& db) {
  Statement q(db.handle(),
              "SELECT name FROM sqlite_master WHERE type='table' AND name NOT LIKE 'sqlite\\_%' ESCAPE '\\'");
  std::set<std::string> names;
  while (q.step()) names.insert(q.column_text(0));
  return names;
}

std::set<std::string> column_names(Database& db, const std::string& table) {
  Statement q(db.handle(), "SELECT name FROM pragma_table_info(?)");
  q.bind(1, table);
  std::set<std::string> names;
  while (q.step()) names.insert(q.column_text(0));
  return names;
}

[[noreturn]] void not_ours(Database& db, const std::string& why) {
  throw StoreError("database '" + db.path() + "' is not a harness database (" + why + "); nothing was written");
}

// the first required column of `table` missing at `version`, or empty
std::string missing_column(Database& db, const std::string& table, int version) {
  const auto have = column_names(db, table);
  const auto required = required_columns(version);
  for (const auto& c : required.at(table))
    if (!have.count(c)) return c;
  return {};
}

}  // namespace

int check_schema(Database& db) {
  const auto tables = table_names(db);
  if (tables.empty()) return 0;
  if (!tables.count("meta")) not_ours(db, "it has tables but no 'meta' table");
  if (const auto c = missing_column(db, "meta", 1); !c.empty()) not_ours(db, "table 'meta' has no column '" + c + "'");

  Statement q(db.handle(), "SELECT value FROM meta WHERE key='schema_version'");
  if (!q.step()) not_ours(db, "no meta.schema_version");
  const std::string text = q.column_text(0);
  const bool digits = !text.empty() && text.size() < 9 &&
      std::all_of(text.begin(), text.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
  const int version = digits ? std::stoi(text) : 0;
  if (version < 1) not_ours(db, "meta.schema_version is '" + text + "', not a version number");
  if (version > kSchemaVersion)
    throw StoreError("database '" + db.path() + "' has schema_version " + text + ", newer than this harness (" +
                     std::to_string(kSchemaVersion) + "): use a newer harness; nothing was written");

  for (const auto& [table, cols] : required_columns(version)) {
    if (!tables.count(table)) not_ours(db, "schema_version " + text + " but no table '" + table + "'");
    if (const auto c = missing_column(db, table, version); !c.empty())
      not_ours(db, "table '" + table + "' has no column '" + c + "' of schema_version " + text);
  }
  return version;
}

int require_harness_tables(Database& db) {
  const int version = check_schema(db);
  if (version == 0) not_ours(db, "it has no tables");
  return version;
}

void prepare_schema(Database& db) {
  // refuse a foreign or newer file before the first write; an existing SQLite file without any
  // table is somebody's database too (only a missing or 0-byte file becomes a new one)
  if (check_schema(db) == 0) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(db.path(), ec);
    if (!ec && size > 0) not_ours(db, "it is a SQLite database without harness tables");
  }
  db.exec("PRAGMA foreign_keys=OFF");  // a migration may rebuild a referenced table (2 -> 3)
  Transaction tx(db);
  // again under the write lock: another process may have created or migrated the file meanwhile
  int version = check_schema(db);
  if (version == 0) {
    db.exec(create_schema_sql());
    Statement meta(db.handle(), "INSERT INTO meta(key, value) VALUES ('schema_version', ?)");
    meta.bind(1, std::to_string(kSchemaVersion)).run();
  } else if (version < kSchemaVersion) {
    // the chain of steps, in order, all in this transaction
    while (version < kSchemaVersion) {
      const auto chain = migrations();
      const auto step = std::find_if(chain.begin(), chain.end(), [&](const Migration& m) { return m.from == version; });
      if (step == chain.end()) throw StoreError("no migration from schema_version " + std::to_string(version));
      db.exec(step->sql);
      ++version;
    }
    Statement meta(db.handle(), "UPDATE meta SET value=? WHERE key='schema_version'");
    meta.bind(1, std::to_string(kSchemaVersion)).run();
  }
  tx.commit();
  // after the schema exists: a file is never left with WAL's header but no harness tables
  db.exec("PRAGMA journal_mode=WAL");
  db.exec("PRAGMA synchronous=NORMAL");
  db.exec("PRAGMA foreign_keys=ON");
}

}  // namespace dsb
