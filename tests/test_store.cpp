// The SQLite store on real files: schema, WAL, run lifecycle, NaN as NULL, resume keys, refusal
// of a foreign schema without touching the file.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "common/config_hash.hpp"
#include "harness/store.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dsb_store_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = (dir_ / "r.sqlite").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  static RunKey key(int seed) { return {"sphere-2", "random", seed, 3, "aaaa", "bbbb"}; }
  static RunResult result() {
    RunResult r;
    r.status = "done";
    r.episodes = 3;
    r.failed_episodes = 1;
    r.best_loss = 0.5;
    r.best_x = {0.25, -0.5};
    r.evals = {{0, 2.0, 2.0, false, 0.1},
               {1, std::nan(""), 2.0, true, 0.1},
               {2, 0.5, 0.5, false, 0.1}};
    return r;
  }
  std::string query(const std::string& sql) {
    Database db(path_, Database::Mode::read_only);
    Statement q(db.handle(), sql);
    std::ostringstream out;
    while (q.step()) out << (q.column_is_null(0) ? "NULL" : q.column_text(0)) << ";";
    return out.str();
  }

  fs::path dir_;
  std::string path_;
};

// the canonical text behind config hashes, as common/config_hash.hpp documents it
TEST(ConfigHash, CanonicalJsonSortsKeysAndPrintsRoundTripDoubles) {
  const nlohmann::json j = {{"b", 0.1},  {"a", 1.0},      {"c", 1e-9},     {"d", 1.0 / 3.0},
                            {"k", 5},    {"n", std::nan("")}, {"i", INFINITY}};
  EXPECT_EQ(canonical_json(j),
            R"({"a":1.0,"b":0.1,"c":1e-09,"d":0.3333333333333333,"i":null,"k":5,"n":null})");
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
  EXPECT_EQ(query("SELECT value FROM meta WHERE key='schema_version'"), "1;");
  EXPECT_EQ(query("SELECT name FROM sqlite_master WHERE type='table' ORDER BY name"),
            "configs;evals;meta;runs;");
}

TEST_F(StoreTest, RunLifecycleCommitsEvalsWithTheStatus) {
  Store store(path_, {"0.1.0", "abc", "host"});
  const auto id = store.begin_run(key(0), 0x1234, {{"env", 1}}, {{"opt", 2}});
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
  const auto id = store.begin_run(key(1), 1, {}, {});
  store.finish_run(id, result());
  const auto id2 = store.begin_run(key(1), 1, {}, {});
  EXPECT_EQ(id, id2);
  EXPECT_EQ(query("SELECT status FROM runs"), "running;");
  store.finish_run(id2, result());
  EXPECT_EQ(query("SELECT count(*) FROM evals"), "3;");
  EXPECT_EQ(query("SELECT count(*) FROM runs"), "1;");
}

TEST_F(StoreTest, AnUnfinishedRunIsNotDoneAfterReopening) {
  {
    Store store(path_, {"0.1.0", "abc", "host"});
    store.finish_run(store.begin_run(key(0), 1, {}, {}), result());
    store.begin_run(key(1), 1, {}, {});  // "killed" before finish_run
  }
  Store again(path_, {"0.1.0", "abc", "host"});
  const auto done = again.done_keys();
  EXPECT_EQ(done.size(), 1u);
  EXPECT_EQ(done.count(key(1)), 0u);
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST_F(StoreTest, RefusesAnotherSchemaVersionWithoutTouchingTheFile) {
  {
    Store store(path_, {"0.1.0", "abc", "host"});
    store.db().exec("UPDATE meta SET value='99' WHERE key='schema_version'");
  }
  const std::string before = file_bytes(path_);
  EXPECT_THROW(Store(path_, {"0.1.0", "abc", "host"}), StoreError);
  EXPECT_EQ(file_bytes(path_), before);
}

TEST_F(StoreTest, UnwritablePathThrowsNamingIt) {
  try {
    Store store((dir_ / "missing" / "r.sqlite").string(), {});
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("missing/r.sqlite"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Store(dir_.string(), {}), StoreError);  // a directory
}

TEST_F(StoreTest, NotADatabaseIsRefusedAndLeftAlone) {
  { std::ofstream(path_) << "hello, this is not SQLite\n"; }
  const std::string before = file_bytes(path_);
  EXPECT_THROW(Store(path_, {}), StoreError);
  EXPECT_EQ(file_bytes(path_), before);
}

}  // namespace
}  // namespace dsb
