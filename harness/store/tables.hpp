#pragma once
// Every table of a harness database, declared once: its columns in order, each with its SQL type
// and constraints, its default, the comment its CREATE TABLE carries and the schema version that
// added it. The schema of a new file, the column lists a migration copies, the store's and
// merge's INSERTs and the reading commands' SELECTs are all derived from these declarations
// (docs/database.md). A new column is one line here (plus a migration step in schema.cpp when it
// changes the schema version): it goes last, so a migrated file and a new one keep one order.
#include <string>
#include <vector>

namespace dsb {

struct Column {
  const char* name;
  const char* type;         // SQL type and constraints, e.g. "TEXT NOT NULL"
  const char* default_sql;  // the SQL DEFAULT value, nullptr for none (NULL)
  const char* comment;      // the -- comment in CREATE TABLE, "" for none
  int since = 1;            // the schema version that added the column
  int key_since = 0;        // the version from which it is in the table's UNIQUE key, 0: never
};

struct Table {
  const char* name;
  std::vector<Column> columns;  // in schema order
  const char* primary_key;      // a PRIMARY KEY(...) table constraint's columns, "" for none
  bool without_rowid;
  int since = 1;  // the schema version that added the table
};

// the tables, in the order a new file creates them
const Table& meta_table();
const Table& configs_table();
const Table& runs_table();
const Table& evals_table();
const Table& replay_table();
const Table& prefix_table();
const std::vector<const Table*>& all_tables();

// CREATE TABLE for `table` as of schema `version` under `name` (a migration builds a table beside
// the old one), with the columns that version has and its UNIQUE key; one statement ending ";\n"
std::string create_table_sql(const Table& table, int version, const std::string& name);

// the columns of `table` at schema `version`, in order
std::vector<const Column*> columns_at(const Table& table, int version);
// their names joined with ", ", leaving out `skip` (e.g. "run_id") when given
std::string column_names(const Table& table, int version, const std::string& skip = "");
// the UNIQUE key's columns at `version`, in order; unique_key joins them with ", " ("" for none)
std::vector<std::string> unique_key_columns(const Table& table, int version);
std::string unique_key(const Table& table, int version);
// a column's DEFAULT as SQL, "NULL" where it has none
std::string default_value(const Column& column);
// "?, ?, ..., ?" for n parameters
std::string placeholders(int n);

// SQL that reads `column` from a file of schema `version`: the column itself, its default where
// the file may hold NULL for it (COALESCE), or its default (or NULL) where the file is older than
// the column
std::string read_column(const Table& table, const std::string& column, int version);
// read_column of every column of `table` but `skip`, joined with ", " (in schema order)
std::string read_columns(const Table& table, int version, const std::string& skip = "");
// the 0-based position of `column` among the columns of `table` but `skip`; throws when absent
int column_index(const Table& table, const std::string& column, const std::string& skip = "");

}  // namespace dsb
