#include "harness/store/schema.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <vector>

#include "harness/store/tables.hpp"

namespace dsb {

namespace {

// the newest schema, for a new file: every table as declared (harness/store/tables.hpp)
std::string create_schema_sql() {
  std::string sql;
  for (const Table* t : all_tables()) sql += create_table_sql(*t, kSchemaVersion, t->name);
  return sql;
}

// One step of the chain: SQL that takes a database of version `from` to version from + 1, derived
// from the declarations. A table whose UNIQUE key changes is rebuilt beside the old one (SQLite
// cannot change a UNIQUE constraint; run_ids are kept, so evals still point at their runs, and
// prepare_schema migrates with foreign keys off) with the columns of the new version, copying the
// old ones; another table gets the version's new columns added at its end; then the tables the
// version adds are created. So a migrated file has the same columns, in the same order, as a new one.
std::string upgrade_sql(int from) {
  const int to = from + 1;
  std::string sql;
  for (const Table* t : all_tables()) {
    if (t->since > from) continue;
    if (unique_key(*t, from) != unique_key(*t, to)) {
      const std::string rebuilt = std::string(t->name) + "_v" + std::to_string(to);
      std::string reads;
      for (const Column* c : columns_at(*t, from))
        reads += (reads.empty() ? "" : ", ") + read_column(*t, c->name, from);
      sql += create_table_sql(*t, to, rebuilt) + "INSERT INTO " + rebuilt + "(" + column_names(*t, from) + ") SELECT " +
          reads + " FROM " + t->name + ";DROP TABLE " + t->name + ";ALTER TABLE " + rebuilt + " RENAME TO " + t->name +
          ";";
      continue;
    }
    for (const Column& c : t->columns)
      if (c.since == to)
        sql += "ALTER TABLE " + std::string(t->name) + " ADD COLUMN " + c.name + " " + c.type +
            (c.default_sql ? " DEFAULT " + std::string(c.default_sql) : "") + ";";
  }
  for (const Table* t : all_tables())
    if (t->since == to) sql += create_table_sql(*t, to, t->name);
  return sql;
}

// The columns every table must have at a version (a file may have more).
std::map<std::string, std::vector<std::string>> required_columns(int version) {
  std::map<std::string, std::vector<std::string>> cols;
  for (const Table* t : all_tables())
    if (t->since <= version)
      for (const Column* c : columns_at(*t, version)) cols[t->name].push_back(c->name);
  return cols;
}

std::set<std::string> table_names(Database& db) {
  Statement q(db.handle(),
              "SELECT name FROM sqlite_master WHERE type='table' AND name NOT LIKE 'sqlite\\_%' ESCAPE '\\'");
  std::set<std::string> names;
  while (q.step()) names.insert(q.column_text(0));
  return names;
}

std::set<std::string> columns_in_file(Database& db, const std::string& table) {
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
  const auto have = columns_in_file(db, table);
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
    for (; version < kSchemaVersion; ++version) db.exec(upgrade_sql(version));
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
