// The SQLite store on real files: schema, WAL, run lifecycle, NaN as NULL, resume keys, run
// diagnostics, the in-place migration of files of versions 1-4, refusal of a foreign or newer file
// without touching it.
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <span>
#include <sstream>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "common/config_hash.hpp"
#include "common/error.hpp"
#include "harness/store/merge.hpp"
#include "harness/store/store.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

class StoreTest : public dsb::testing::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    path_ = path("r.sqlite");
  }

  static RunKey key(int seed) { return {"sphere-2", "random", seed, 3, "aaaa", "bbbb", "0.1.0"}; }
  static RunResult result() {
    RunResult r;
    r.status = RunStatus::done;
    r.episodes = 3;
    r.failed_episodes = 1;
    r.best_loss = 0.5;
    r.best_x = {0.25, -0.5};
    r.evals = {{0, 2.0, 2.0, false, 0.1}, {1, std::nan(""), 2.0, true, 0.1}, {2, 0.5, 0.5, false, 0.1}};
    return r;
  }
  std::string query(const std::string& sql) {
    Database db(path_, Database::Mode::read_only);
    Statement q(db.handle(), sql);
    std::ostringstream out;
    while (q.step()) out << (q.column_is_null(0) ? "NULL" : q.column_text(0)) << ";";
    return out.str();
  }

  std::string path_;
};

// the canonical text behind config hashes, as common/config_hash.hpp documents it
TEST(ConfigHash, CanonicalJsonSortsKeysAndPrintsRoundTripDoubles) {
  const nlohmann::json j = {{"b", 0.1}, {"a", 1.0},          {"c", 1e-9},    {"d", 1.0 / 3.0},
                            {"k", 5},   {"n", std::nan("")}, {"i", INFINITY}};
  EXPECT_EQ(canonical_json(j), R"({"a":1.0,"b":0.1,"c":1e-09,"d":0.3333333333333333,"i":null,"k":5,"n":null})");
  // every double reads back exactly, so neighbouring doubles hash apart
  const double x = 0.1, next = std::nextafter(x, 1.0);
  EXPECT_EQ(std::stod(canonical_json(nlohmann::json(next))), next);
  EXPECT_NE(config_hash({{"lr", x}}), config_hash({{"lr", next}}));
  EXPECT_NE(config_hash({{"lr", 5}}), config_hash({{"lr", 5.0}}));
  EXPECT_EQ(config_hash({{"lr", 1.0}}).size(), 16u);
}

TEST_F(StoreTest, CreatesTheSchemaInWalModeWithItsVersion) {
  Store store(path_, {"0.1.0", "abc", "host"});
  EXPECT_EQ(query("PRAGMA journal_mode"), "wal;");
  EXPECT_EQ(query("SELECT value FROM meta WHERE key='schema_version'"), "6;");
  EXPECT_EQ(query("SELECT name FROM sqlite_master WHERE type='table' ORDER BY name"),
            "configs;evals;meta;prefix;replay;runs;");
}

TEST_F(StoreTest, RunLifecycleCommitsEvalsWithTheStatus) {
  Store store(path_, {"0.1.0", "abc", "host"});
  const auto id = store.begin_run(key(0), 0x1234, {{"env", 1}}, {{"opt", 2}}).run_id;
  EXPECT_EQ(query("SELECT status FROM runs"), "running;");
  EXPECT_EQ(query("SELECT count(*) FROM evals"), "0;");
  EXPECT_TRUE(store.done_keys().empty());
  store.finish_run(id, result());
  EXPECT_EQ(query("SELECT status || ',' || episodes || ',' || best_loss || ',' || best_x || ',' || rng_seed FROM runs"),
            "done,3,0.5,[0.25,-0.5],0000000000001234;");
  // the failed episode's loss is NULL (SQLite has no NaN) and flagged
  EXPECT_EQ(query("SELECT loss FROM evals ORDER BY episode"), "2.0;NULL;0.5;");
  EXPECT_EQ(query("SELECT failed FROM evals ORDER BY episode"), "0;1;0;");
  EXPECT_EQ(query("SELECT kind FROM configs ORDER BY kind"), "env;optimizer;");
  EXPECT_EQ(store.done_keys().size(), 1u);
  EXPECT_EQ(store.done_keys().count(key(0)), 1u);
}

TEST_F(StoreTest, RedoingARunReusesItsRowAndReplacesItsEvals) {
  Store store(path_, {"0.1.0", "abc", "host"});
  const auto id = store.begin_run(key(1), 1, {}, {}).run_id;
  store.finish_run(id, result());
  const auto id2 = store.begin_run(key(1), 1, {}, {}).run_id;
  EXPECT_EQ(id, id2);
  EXPECT_EQ(query("SELECT status FROM runs"), "running;");
  store.finish_run(id2, result());
  EXPECT_EQ(query("SELECT count(*) FROM evals"), "3;");
  EXPECT_EQ(query("SELECT count(*) FROM runs"), "1;");
}

TEST_F(StoreTest, AnUnfinishedRunIsNotDoneAfterReopening) {
  {
    Store store(path_, {"0.1.0", "abc", "host"});
    store.finish_run(store.begin_run(key(0), 1, {}, {}).run_id, result());
    store.begin_run(key(1), 1, {}, {}).run_id;  // "killed" before finish_run
  }
  Store again(path_, {"0.1.0", "abc", "host"});
  const auto done = again.done_keys();
  EXPECT_EQ(done.size(), 1u);
  EXPECT_EQ(done.count(key(1)), 0u);
}

TEST_F(StoreTest, RefusesANewerSchemaVersionWithoutTouchingTheFile) {
  {
    Store store(path_, {"0.1.0", "abc", "host"});
    store.db().exec("UPDATE meta SET value='7' WHERE key='schema_version'");
  }
  const std::string before = testing::read_file(path_);
  try {
    Store again(path_, {"0.1.0", "abc", "host"});
    FAIL() << "a schema_version 7 file was opened";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("schema_version 7, newer than this harness (6)"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(testing::read_file(path_), before);
}

TEST_F(StoreTest, StoresTheRunDiagnosticsAsJsonAndTheMetricAsNull) {
  Store store(path_, {"0.1.0", "abc", "host"});
  const auto id = store.begin_run(key(0), 1, {}, {}).run_id;
  RunResult r = result();
  r.evals[2].metric = 0.75;
  r.diagnostics = {{"optimizer", {{"restarts", 2}}}, {"objective", {{"episodes", 3}}}};
  store.finish_run(id, r);
  EXPECT_EQ(query("SELECT diagnostics FROM runs"), R"({"objective":{"episodes":3},"optimizer":{"restarts":2}};)");
  EXPECT_EQ(query("SELECT metric FROM evals ORDER BY episode"), "NULL;NULL;0.75;");
  // redoing the run clears the diagnostics until it finishes again
  store.begin_run(key(0), 1, {}, {}).run_id;
  EXPECT_EQ(query("SELECT diagnostics FROM runs"), "NULL;");
}

// ---------------------------------------------------------------------------------------------
// version 1 files

// a frozen SQL text of an older version (tests/fixtures/store/NAME); a test fails on a missing one
std::string fixture(const std::string& name) {
  const std::string path = std::string(DSB_SOURCE_DIR) + "/tests/fixtures/store/" + name;
  const std::string sql = testing::read_file(path);
  EXPECT_FALSE(sql.empty()) << "missing fixture " << path;
  return sql;
}

const char* kRunsV1Columns =
    "run_id, env, optimizer, seed, budget, env_config_hash, opt_config_hash, rng_seed, status, episodes, "
    "failed_episodes, best_loss, best_x, wall_s, error, started_at, finished_at, harness_version, git_sha, host";
const char* kEvalsV1Columns = "run_id, episode, loss, best_loss, used_grad, wall_s, failed";
// a file's rows of the version-1 columns, which every later version keeps
const std::string kRunsV1Query = std::string("SELECT ") + kRunsV1Columns + " FROM runs ORDER BY run_id";
const std::string kEvalsV1Query = std::string("SELECT ") + kEvalsV1Columns + " FROM evals ORDER BY run_id, episode";

// every value of a query, exactly: integers as integers, reals by their 64 bits, texts, NULLs
std::string exact_rows(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* q = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  std::ostringstream out;
  while (sqlite3_step(q) == SQLITE_ROW) {
    for (int c = 0; c < sqlite3_column_count(q); ++c) {
      switch (sqlite3_column_type(q, c)) {
        case SQLITE_INTEGER: out << "i" << sqlite3_column_int64(q, c); break;
        case SQLITE_FLOAT: {
          char hex[32];
          std::snprintf(hex, sizeof hex, "%016llx",
                        static_cast<unsigned long long>(std::bit_cast<std::uint64_t>(sqlite3_column_double(q, c))));
          out << "f" << hex;
          break;
        }
        case SQLITE_TEXT: out << "t" << reinterpret_cast<const char*>(sqlite3_column_text(q, c)); break;
        case SQLITE_NULL: out << "n"; break;
        default: out << "b" << sqlite3_column_bytes(q, c); break;
      }
      out << "|";
    }
    out << "\n";
  }
  sqlite3_finalize(q);
  sqlite3_close(db);
  return out.str();
}

// A version-1 file as the version-1 harness left it (WAL), with awkward values: a failed episode
// (NULL loss), a subnormal, 0.1, a huge loss, a 'running' run without evals, a failed run.
void write_version1_file(const std::string& path) {
  Database db(path);
  db.exec("PRAGMA journal_mode=WAL");
  db.exec(fixture("schema_v1.sql"));
  db.exec(R"sql(
    INSERT INTO meta VALUES ('schema_version', '1');
    INSERT INTO configs VALUES ('e1', 'env', '{"dim":2}'), ('o1', 'optimizer', '{"sigma0":0.5}');
    INSERT INTO runs VALUES
      (1, 'sphere-2', 'cmaes', 0, 3, 'e1', 'o1', '00000000deadbeef', 'done', 3, 1, 4.9406564584124654e-324,
       '[0.1,-0.30000000000000004]', 0.012345678901234567, NULL, '2024-01-01T00:00:00Z', '2024-01-01T00:00:01Z',
       '0.1.0', 'abc123', 'node-1'),
      (2, 'sphere-2', 'cmaes', 1, 3, 'e1', 'o1', '0000000000000002', 'running', 0, 0, NULL, NULL, NULL, NULL,
       '2024-01-01T00:00:02Z', NULL, '0.1.0', 'abc123', 'node-1'),
      (3, 'branin', 'gd', 0, 2, 'e1', 'o1', 'ffffffffffffffff', 'failed', 2, 0, 0.1, '[1,-1]', 1e-3,
       'cmaes: eigendecomposition of C failed', '2024-01-01T00:00:03Z', '2024-01-01T00:00:04Z', '0.1.0', 'abc123',
       'node-2');
    INSERT INTO evals VALUES
      (1, 0, 1.7976931348623157e308, 1.7976931348623157e308, 0, 1e-6, 0),
      (1, 1, NULL, 1.7976931348623157e308, 1, 2e-6, 1),
      (1, 2, 4.9406564584124654e-324, 4.9406564584124654e-324, 0, 3e-6, 0),
      (3, 0, 0.30000000000000004, 0.30000000000000004, 1, 0.5, 0),
      (3, 1, 0.1, 0.1, 1, 0.25, 0);
  )sql");
}

// A table's shape, as SQLite reports it: each column's name, type, NOT NULL, default and primary
// key position, in order, then each index's uniqueness, origin and columns (index names left out:
// an index made for a rebuilt table is named after the table it was built as).
std::string table_shape(const std::string& path, const std::string& table) {
  const std::string t = "'" + table + "'";
  return exact_rows(path, "SELECT name, type, \"notnull\", dflt_value, pk FROM pragma_table_info(" + t + ")") +
      exact_rows(path,
                 "SELECT il.\"unique\", il.origin, ii.seqno, ii.name FROM pragma_index_list(" + t +
                     ") il JOIN pragma_index_info(il.name) ii ORDER BY il.seq, ii.seqno");
}

// every table of a harness database, each with the shape of a new file's
void expect_tables_of_a_new_file(const std::string& path, const std::string& fresh) {
  { Store store(fresh, {}); }
  for (const char* table : {"meta", "configs", "runs", "evals", "replay", "prefix"})
    EXPECT_EQ(table_shape(path, table), table_shape(fresh, table)) << table;
  EXPECT_EQ(exact_rows(path, "SELECT name FROM sqlite_master WHERE type='table' ORDER BY name"),
            exact_rows(fresh, "SELECT name FROM sqlite_master WHERE type='table' ORDER BY name"));
}

TEST_F(StoreTest, MigratesAVersion1FileInPlaceKeepingEveryRowBitForBit) {
  write_version1_file(path_);
  const std::string configs_sql = "SELECT hash, kind, json FROM configs ORDER BY hash";
  const std::string runs_before = exact_rows(path_, kRunsV1Query), evals_before = exact_rows(path_, kEvalsV1Query),
                    configs_before = exact_rows(path_, configs_sql);
  ASSERT_EQ(query("SELECT count(*) FROM evals"), "5;");
  ASSERT_EQ(query("SELECT value FROM meta WHERE key='schema_version'"), "1;");

  {
    Store store(path_, {"0.2.0", "def", "host"});
    // what was done stays in the file, under a key without results versions: made before them, so
    // stale for this binary, whose keys carry its versions (docs/database.md "Results versions")
    const auto done = store.done_keys();
    ASSERT_EQ(done.size(), 1u);
    EXPECT_EQ(done.begin()->versions, ResultsVersions{});
  }
  EXPECT_EQ(query("SELECT value FROM meta WHERE key='schema_version'"), "6;");
  EXPECT_EQ(exact_rows(path_, kRunsV1Query), runs_before);
  EXPECT_EQ(exact_rows(path_, kEvalsV1Query), evals_before);
  EXPECT_EQ(exact_rows(path_, configs_sql), configs_before);
  // the new columns, after the old ones, NULL in old rows (shared_episodes 0: nothing was shared)
  EXPECT_EQ(query("SELECT name FROM pragma_table_info('runs') WHERE cid >= 20"),
            "diagnostics;seed_free_episodes;seed_free_calls;shared_episodes;shared_from_seed;results_versions;cpu_s;");
  EXPECT_EQ(query("SELECT count(*) FROM runs WHERE results_versions = ''"), "3;");
  EXPECT_EQ(query("SELECT count(*) FROM runs WHERE cpu_s IS NULL"), "3;");
  EXPECT_EQ(query("SELECT count(*) FROM runs WHERE seed_free_episodes IS NULL AND seed_free_calls IS NULL AND "
                  "shared_episodes = 0 AND shared_from_seed IS NULL"),
            "3;");
  EXPECT_EQ(query("SELECT name FROM pragma_table_info('evals') WHERE cid >= 7"), "metric;");
  EXPECT_EQ(query("SELECT count(*) FROM runs WHERE diagnostics IS NULL"), "3;");
  EXPECT_EQ(query("SELECT count(*) FROM evals WHERE metric IS NULL"), "5;");
  // a migrated file has the columns of a new one, in the same order, and the same keys
  expect_tables_of_a_new_file(path_, (dir_ / "fresh.sqlite").string());

  // and it takes new runs with diagnostics; opening it again changes nothing
  {
    Store store(path_, {"0.2.0", "def", "host"});
    const auto id = store.begin_run(key(5), 5, {}, {}).run_id;
    RunResult r = result();
    r.diagnostics = {{"optimizer", nlohmann::json::object()}, {"objective", {{"episodes", 3}}}};
    store.finish_run(id, r);
  }
  EXPECT_EQ(query("SELECT count(*) FROM runs WHERE diagnostics IS NOT NULL"), "1;");
  EXPECT_EQ(exact_rows(path_, kEvalsV1Query + " LIMIT 5"), evals_before);
}

// The steps that made versions 2, 3 and 4 of a file, frozen (tests/fixtures/store/step_*.sql):
// a file of version 1 plus steps 1..v-1 is a file of version v.
// step v - 1 -> v as SQL
std::string step_to_version(int v) {
  return fixture("step_" + std::to_string(v - 1) + "_to_" + std::to_string(v) + ".sql");
}

// the version-1 file, taken to `version` by the steps that made that version
void write_version_file(const std::string& path, int version) {
  write_version1_file(path);
  Database db(path);
  for (int v = 2; v <= version; ++v) db.exec(step_to_version(v));
  db.exec("UPDATE meta SET value='" + std::to_string(version) + "' WHERE key='schema_version'");
}

TEST_F(StoreTest, EveryOlderVersionMigratesToTheTablesOfANewFileKeepingItsRows) {
  for (int version = 2; version < kSchemaVersion; ++version) {
    SCOPED_TRACE("schema_version " + std::to_string(version));
    const std::string file = path("v" + std::to_string(version) + ".sqlite");
    write_version_file(file, version);
    const std::string runs_before = exact_rows(file, kRunsV1Query), evals_before = exact_rows(file, kEvalsV1Query);
    { Store store(file, {"0.2.0", "def", "host"}); }
    EXPECT_EQ(exact_rows(file, "SELECT value FROM meta WHERE key='schema_version'"), "t6|\n");
    EXPECT_EQ(exact_rows(file, "SELECT count(*) FROM runs WHERE cpu_s IS NULL"), "i3|\n");
    EXPECT_EQ(exact_rows(file, kRunsV1Query), runs_before);
    EXPECT_EQ(exact_rows(file, kEvalsV1Query), evals_before);
    EXPECT_EQ(exact_rows(file, "SELECT count(*) FROM runs WHERE results_versions = '' AND shared_episodes = 0"),
              "i3|\n");
    expect_tables_of_a_new_file(file, path("fresh" + std::to_string(version) + ".sqlite"));
  }
}

// merge reads a file of any version as it is (read-only): a column the file lacks as its default
TEST_F(StoreTest, MergeCopiesTheRunsOfAFileOfEveryOlderVersion) {
  for (int version = 1; version <= 4; ++version) {
    SCOPED_TRACE("schema_version " + std::to_string(version));
    const std::string input = path("in" + std::to_string(version) + ".sqlite");
    write_version_file(input, version);
    const std::string input_bytes = testing::read_file(input);
    const std::string out = path("merged" + std::to_string(version) + ".sqlite");
    {
      Store store(out, {});
      const MergeCounts n = merge_inputs(store, {input});
      EXPECT_EQ(n.added, 3);
    }
    EXPECT_EQ(testing::read_file(input), input_bytes);
    // the same rows, under the same run_ids (the output was empty), with the defaults of the rest
    EXPECT_EQ(exact_rows(out, kRunsV1Query), exact_rows(input, kRunsV1Query));
    EXPECT_EQ(exact_rows(out, kEvalsV1Query), exact_rows(input, kEvalsV1Query));
    EXPECT_EQ(exact_rows(out,
                         "SELECT count(*) FROM runs WHERE diagnostics IS NULL AND shared_episodes = 0 AND "
                         "results_versions = ''"),
              "i3|\n");
    EXPECT_EQ(exact_rows(out, "SELECT count(*) FROM evals WHERE metric IS NULL"), "i5|\n");
  }
}

TEST_F(StoreTest, AFailedMigrationStepRollsBackTheWholeChain) {
  write_version1_file(path_);
  // a version-1 file that already has a column named like version 2's evals.metric (extra
  // columns are allowed): the second statement of the step fails after the first one succeeded
  {
    Database db(path_);
    db.exec("ALTER TABLE evals ADD COLUMN metric TEXT");
  }
  EXPECT_THROW(Store(path_, {}), StoreError);
  EXPECT_EQ(query("SELECT value FROM meta WHERE key='schema_version'"), "1;");
  EXPECT_EQ(query("SELECT count(*) FROM pragma_table_info('runs') WHERE name='diagnostics'"), "0;");
}

// ---------------------------------------------------------------------------------------------
// files that are not harness databases: refused before anything is written

TEST_F(StoreTest, ForeignDatabasesAreRefusedAndLeftAlone) {
  struct Case {
    const char* name;
    const char* sql;
    const char* message;
  };
  const Case cases[] = {
      {"tables of our names, no meta", "CREATE TABLE runs(id INTEGER, name TEXT); CREATE TABLE evals(x REAL);",
       "no 'meta' table"},
      {"an unrelated table", "CREATE TABLE users(id INTEGER PRIMARY KEY, email TEXT);", "no 'meta' table"},
      {"meta without schema_version",
       "CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT); INSERT INTO meta VALUES ('owner', 'x');",
       "no meta.schema_version"},
      {"meta of another shape", "CREATE TABLE meta(name TEXT, version INTEGER);", "table 'meta' has no column 'key'"},
      {"a version that is not a number",
       "CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT); INSERT INTO meta VALUES ('schema_version', 'v2');",
       "meta.schema_version is 'v2'"},
      {"our version, other runs columns",
       "CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT); INSERT INTO meta VALUES ('schema_version', '2');"
       "CREATE TABLE configs(hash, kind, json); CREATE TABLE runs(run_id INTEGER PRIMARY KEY, title TEXT);"
       "CREATE TABLE evals(run_id, episode, loss, best_loss, used_grad, wall_s, failed, metric);",
       "table 'runs' has no column 'env'"},
      {"version 1 without evals",
       "CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT); INSERT INTO meta VALUES ('schema_version', '1');",
       "no table 'configs'"},
  };
  for (const auto& c : cases) {
    const std::string path = (dir_ / (std::string(c.name) + ".sqlite")).string();
    {
      Database db(path);
      db.exec(c.sql);
    }
    const std::string before = testing::read_file(path);
    try {
      Store store(path, {});
      ADD_FAILURE() << c.name << ": opened";
    } catch (const StoreError& e) {
      EXPECT_NE(std::string(e.what()).find("is not a harness database"), std::string::npos)
          << c.name << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << c.name << ": " << e.what();
    }
    EXPECT_EQ(testing::read_file(path), before) << c.name;
    EXPECT_FALSE(fs::exists(path + "-wal") && fs::file_size(path + "-wal") > 0) << c.name;
  }
}

TEST_F(StoreTest, ARunningRunKeepsItsCommittedEpisodesAndJournalUntilItIsDone) {
  const double nan_payload = std::bit_cast<double>(0x7ff8000000000123ULL);  // a NaN with payload bits
  std::vector<ReplayEntry> journal = {
      {ReplayKind::value_and_grad, 0x8000000000000001ULL, {0.5, nan_payload, 1e-3, -0.0}},
      {ReplayKind::rl_reset, 42, {}},
      {ReplayKind::rl_step, 7, {1.0, std::numeric_limits<double>::infinity()}}};
  const std::vector<EvalRecord> evals = {{0, 2.0, 2.0, true, 0.1}, {1, std::nan(""), 2.0, false, 0.1}};
  {
    Store store(path_, {"0.1.0", "abc", "host"});
    const auto id = store.begin_run(key(0), 1, {}, {}).run_id;
    store.append_progress(id, evals, 0, journal);
    EXPECT_EQ(query("SELECT episodes FROM runs"), "2;");
  }
  Store again(path_, {"0.1.0", "abc", "host"});
  EXPECT_TRUE(again.done_keys().empty());
  const RunStart start = again.begin_run(key(0), 1, {}, {});
  EXPECT_EQ(start.committed_episodes, 2);
  ASSERT_EQ(start.journal.size(), 3u);
  for (std::size_t k = 0; k < journal.size(); ++k) {
    EXPECT_EQ(start.journal[k].kind, journal[k].kind);
    EXPECT_EQ(start.journal[k].input_hash, journal[k].input_hash);
    ASSERT_EQ(start.journal[k].payload.size(), journal[k].payload.size());
    for (std::size_t i = 0; i < journal[k].payload.size(); ++i)  // bit for bit: NaN payload, -0.0, inf
      EXPECT_EQ(std::bit_cast<std::uint64_t>(start.journal[k].payload[i]),
                std::bit_cast<std::uint64_t>(journal[k].payload[i]));
  }
  again.finish_run(start.run_id, result());
  EXPECT_EQ(query("SELECT count(*) FROM replay"), "0;");
  EXPECT_EQ(query("SELECT count(*) FROM evals"), "3;");
  // a failed run starts over from nothing
  const auto id = again.begin_run(key(1), 1, {}, {}).run_id;
  again.append_progress(id, evals, 0, journal);
  RunResult failed = result();
  failed.status = RunStatus::failed;
  again.finish_run(id, failed);
  const RunStart redo = again.begin_run(key(1), 1, {}, {});
  EXPECT_EQ(redo.committed_episodes, 0);
  EXPECT_TRUE(redo.journal.empty());
}

TEST_F(StoreTest, ARunsCpuSecondsAreStoredAtEachCommitAndComeBackToItsResume) {
  const std::vector<EvalRecord> evals = {{0, 2.0, 2.0, true, 0.1}, {1, 1.0, 1.0, false, 0.1}};
  const std::vector<ReplayEntry> journal = {{ReplayKind::value, 1, {2.0}}, {ReplayKind::value, 2, {1.0}}};
  {
    Store store(path_, {"0.1.0", "abc", "host"});
    const RunStart first = store.begin_run(key(0), 1, {}, {});
    EXPECT_EQ(first.cpu_s, 0.0);  // a new run has spent nothing
    store.append_progress(first.run_id, std::span(evals).first(1), 0, std::vector(journal.begin(), journal.begin() + 1),
                          {}, 1.25);
    EXPECT_EQ(query("SELECT cpu_s FROM runs"), "1.25;");
    store.append_progress(first.run_id, std::span(evals).subspan(1), 1, std::vector(journal.begin() + 1, journal.end()),
                          {}, 2.5);
    EXPECT_EQ(query("SELECT cpu_s FROM runs"), "2.5;");
  }
  {
    Store again(path_, {"0.1.0", "abc", "host"});
    const RunStart resumed = again.begin_run(key(0), 1, {}, {});
    EXPECT_EQ(resumed.committed_episodes, 2);
    EXPECT_EQ(resumed.cpu_s, 2.5);  // what its first session spent, for the runner to add to
    RunResult r = result();
    r.cpu_s = 3.0;
    again.finish_run(resumed.run_id, r);
    EXPECT_EQ(query("SELECT cpu_s FROM runs"), "3.0;");
    // episodes committed without CPU seconds (an older harness, --threads > 1): unknown from then on
    const auto id = again.begin_run(key(1), 1, {}, {}).run_id;
    again.append_progress(id, evals, 0, journal);
    EXPECT_EQ(query("SELECT cpu_s IS NULL FROM runs WHERE run_id=" + std::to_string(id)), "1;");
  }
  Store third(path_, {"0.1.0", "abc", "host"});
  EXPECT_TRUE(std::isnan(third.begin_run(key(1), 1, {}, {}).cpu_s));
}

TEST_F(StoreTest, ADoneRunKeepsItsSeedFreeEpisodesOnceAndAnotherSeedTakesThem) {
  Store store(path_, {"0.1.0", "abc", "host"});
  std::vector<ReplayEntry> journal;
  for (int k = 0; k < 3; ++k) journal.push_back({ReplayKind::value, 100u + k, {0.1 * k, 0.0, 1e-3}});
  // seed 0: two entries committed while running, the third still in the tail when it ends
  const auto id0 = store.begin_run(key(0), 1, {}, {}, /*share=*/true).run_id;
  store.append_progress(id0, std::span<const EvalRecord>(result().evals).first(2), 0,
                        std::vector<ReplayEntry>(journal.begin(), journal.begin() + 2));
  RunResult r0 = result();
  r0.seed_free = {3, 3, false};
  r0.journal_tail = {journal[2]};
  r0.journal_tail_first_seq = 2;
  store.finish_run(id0, r0);
  EXPECT_EQ(query("SELECT run_id || ':' || seq || ':' || input_hash FROM prefix ORDER BY seq"),
            std::to_string(id0) + ":0:100;" + std::to_string(id0) + ":1:101;" + std::to_string(id0) + ":2:102;");
  EXPECT_EQ(query("SELECT seed_free_episodes || ',' || seed_free_calls FROM runs"), "3,3;");
  // seed 1 takes them: copied into its own journal (a resume finds them there) and returned
  const RunStart s1 = store.begin_run(key(1), 2, {}, {}, /*share=*/true);
  EXPECT_EQ(s1.committed_episodes, 0);
  EXPECT_EQ(s1.journal_episodes, 3);
  EXPECT_EQ(s1.shared_episodes, 3);
  EXPECT_EQ(s1.shared_from_seed, 0);
  ASSERT_EQ(s1.journal.size(), 3u);
  EXPECT_EQ(s1.journal[2].input_hash, 102u);
  EXPECT_EQ(query("SELECT count(*) FROM replay WHERE run_id=" + std::to_string(s1.run_id)), "3;");
  EXPECT_EQ(query("SELECT shared_episodes || ',' || shared_from_seed FROM runs WHERE seed=1"), "3,0;");
  // done with the same prefix: kept once in the group
  RunResult r1 = result();
  r1.seed_free = {3, 3, false};
  store.finish_run(s1.run_id, r1);
  EXPECT_EQ(query("SELECT count(DISTINCT run_id) FROM prefix"), "1;");
  EXPECT_EQ(query("SELECT count(*) FROM replay"), "0;");
  // without share, or for a run of another group, nothing is taken
  EXPECT_EQ(store.begin_run(key(2), 3, {}, {}).journal_episodes, 0);
  RunKey other = key(3);
  other.budget = 4;
  EXPECT_EQ(store.begin_run(other, 4, {}, {}, true).journal_episodes, 0);
  // a failed run keeps nothing; a diverged share is forgotten with the progress
  const RunStart s4 = store.begin_run(key(4), 5, {}, {}, true);
  EXPECT_EQ(s4.shared_episodes, 3);
  store.reset_progress(s4.run_id);
  EXPECT_EQ(query("SELECT shared_episodes || ',' || COALESCE(shared_from_seed, 'none') FROM runs WHERE seed=4"),
            "0,none;");
}

TEST_F(StoreTest, RunsOfAnotherHarnessVersionAreOtherRuns) {
  Store store(path_, {"0.2.0", "abc", "host"});
  RunKey old_version = key(0), new_version = key(0);
  old_version.harness_version = "0.1.0";
  new_version.harness_version = "0.2.0";
  store.finish_run(store.begin_run(old_version, 1, {}, {}).run_id, result());
  EXPECT_EQ(store.done_keys().count(new_version), 0u);
  store.finish_run(store.begin_run(new_version, 1, {}, {}).run_id, result());
  EXPECT_EQ(query("SELECT count(*) FROM runs"), "2;");
}

TEST_F(StoreTest, ASecondStoreOnTheSameFileIsRefusedUntilTheFirstCloses) {
  auto first = std::make_unique<Store>(path_, Provenance{"0.1.0", "abc", "host"});
  try {
    Store second(path_, {"0.1.0", "abc", "host"});
    FAIL() << "opened twice";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("is in use by another harness (pid " + std::to_string(::getpid())),
              std::string::npos)
        << e.what();
  }
  first.reset();
  EXPECT_NO_THROW(Store(path_, {"0.1.0", "abc", "host"}));
}

TEST_F(StoreTest, ASqliteFileWithoutTablesIsNotStamped) {
  {
    Database db(path_);
    db.exec("PRAGMA user_version=5; CREATE TABLE t(x); DROP TABLE t;");
  }
  const std::string before = testing::read_file(path_);
  ASSERT_FALSE(before.empty());
  try {
    Store store(path_, {});
    FAIL() << "opened";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("without harness tables"), std::string::npos) << e.what();
  }
  EXPECT_EQ(testing::read_file(path_), before);
}

TEST_F(StoreTest, AnEmptyFileBecomesANewDatabase) {
  { std::ofstream touch(path_); }
  Store store(path_, {});
  EXPECT_EQ(query("SELECT value FROM meta WHERE key='schema_version'"), "6;");
}

TEST_F(StoreTest, UnwritablePathThrowsNamingIt) {
  try {
    Store store((dir_ / "missing" / "r.sqlite").string(), {});
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("missing/r.sqlite"), std::string::npos) << e.what();
  }
  try {
    Store store(dir_.string(), {});  // a directory: bad input, named by its kind
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory, not a regular file"), std::string::npos) << e.what();
  }
}

TEST_F(StoreTest, NotADatabaseIsRefusedAndLeftAlone) {
  { std::ofstream(path_) << "hello, this is not SQLite\n"; }
  const std::string before = testing::read_file(path_);
  EXPECT_THROW(Store(path_, {}), StoreError);
  EXPECT_EQ(testing::read_file(path_), before);
}

}  // namespace
}  // namespace dsb
