#pragma once
// The database schema (docs/database.md "Database"): its version, the SQL of the newest version, and the
// chain of in-place migrations that brings an older harness database up to it.
//
// Versions:
//   1  runs, evals, configs, meta (the first release)
//   2  + runs.diagnostics (JSON: what the optimizer and the objective saw during the run)
//      + evals.metric (REAL, NULL: an optional second per-episode metric)
//   3  runs.harness_version is part of the run key (UNIQUE; NOT NULL, '' for older rows) and the
//      table `replay` holds what a run that is not done yet needs to be resumed by replay
//   4  sharing across seeds: runs.seed_free_episodes and seed_free_calls (the episodes before the
//      optimizer's first draw and their journal entries; NULL where unknown), runs.shared_episodes
//      and shared_from_seed (episodes taken by replay from another seed's run), and the table
//      `prefix`: the journal of a done run's seed-free episodes, which other seeds replay
//   5  results versions (harness/core/results_versions.hpp): runs.results_versions, part of the run key
//      (UNIQUE; '' for the rows of older files, which are therefore stale for this binary)
//   6  runs.cpu_s: the CPU seconds the run's worker thread spent on it, over all its sessions;
//      later changes that altered no table added its thread team's workers' (--threads > 1) and an
//      ext: optimizer's program's (optimizers/ext/process_cpu.hpp). NULL where unknown: rows of
//      older files, and such runs of a harness before those changes
// The tables are declared in harness/store/tables.hpp; the CREATE TABLE of a new file and each
// migration step are derived from them. A later version bumps kSchemaVersion and declares what it
// adds (columns and tables with `since` = the new version, a key column with `key_since`); a step
// that must also change rows adds its SQL to upgrade_sql.
#include <string>

#include "harness/store/sqlite_db.hpp"

namespace dsb {

inline constexpr int kSchemaVersion = 6;

// The schema_version of an opened file: 0 for an empty database (no tables at all). Throws
// StoreError naming the file when it is not a harness database (tables but no meta table, no
// meta.schema_version, a version that is not a number >= 1, tables of our names without the
// columns of that version) or when its version is newer than kSchemaVersion. Reads only.
int check_schema(Database& db);

// check_schema for a command that only reads: also refuses a database without any tables ("is
// not a harness database (it has no tables)"). Returns the version.
int require_harness_tables(Database& db);

// Makes `db` a harness database of version kSchemaVersion: checks it (check_schema, so a
// foreign or newer file is refused before anything is written), switches it to WAL, then in one
// transaction creates the schema (empty file) or applies the migration steps from its version on.
// Throws StoreError; a failed migration is rolled back and leaves the file as it was.
void prepare_schema(Database& db);

}  // namespace dsb
