#pragma once
// Test helper: what a query returns on a database file, read-only through the SQLite C API (not
// through the harness's own store code, so the tests check the file itself).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <sqlite3.h>

namespace dsb::testing {

// rows of a query, columns joined by '|', NULL as "NULL", reals in %a (every bit)
inline std::vector<std::string> rows(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK) << path;
  sqlite3_busy_timeout(db, 10000);  // a harness may be writing it (tests that poll a live grid)
  sqlite3_stmt* q = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr), SQLITE_OK) << sql;
  std::vector<std::string> out;
  while (q && sqlite3_step(q) == SQLITE_ROW) {
    std::string r;
    for (int c = 0; c < sqlite3_column_count(q); ++c) {
      if (c) r += "|";
      if (sqlite3_column_type(q, c) == SQLITE_NULL) {
        r += "NULL";
      } else if (sqlite3_column_type(q, c) == SQLITE_FLOAT) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%a", sqlite3_column_double(q, c));
        r += buf;
      } else {
        r += reinterpret_cast<const char*>(sqlite3_column_text(q, c));
      }
    }
    out.push_back(r);
  }
  sqlite3_finalize(q);
  sqlite3_close(db);
  return out;
}

// the first row of a query ("" when there is none)
inline std::string scalar(const std::string& path, const std::string& sql) {
  const auto r = rows(path, sql);
  return r.empty() ? "" : r[0];
}

// the first column of the first row, "" when there is none or the query fails (a database being
// created: polled until it holds what a test waits for)
inline std::string quiet_scalar(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  std::string v;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(db, 10000);
    sqlite3_stmt* q = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr) == SQLITE_OK && sqlite3_step(q) == SQLITE_ROW &&
        sqlite3_column_text(q, 0))
      v = reinterpret_cast<const char*>(sqlite3_column_text(q, 0));
    sqlite3_finalize(q);
  }
  sqlite3_close(db);
  return v;
}

// one stored episode: (env, optimizer, seed, budget, episode)
using EvalKey = std::tuple<std::string, std::string, int, std::int64_t, std::int64_t>;

// every stored episode's loss (NULL, a failed episode, as NaN) of the runs the SQL condition
// `which_runs` (over runs r) selects
inline std::map<EvalKey, double> stored_losses(const std::string& path, const std::string& which_runs = "1") {
  const std::string sql =
      "SELECT r.env, r.optimizer, r.seed, r.budget, e.episode, e.loss FROM evals e JOIN runs r USING(run_id) "
      "WHERE " +
      which_runs;
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK) << path;
  sqlite3_stmt* q = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr), SQLITE_OK) << sql;
  std::map<EvalKey, double> losses;
  while (q && sqlite3_step(q) == SQLITE_ROW) {
    const EvalKey k{reinterpret_cast<const char*>(sqlite3_column_text(q, 0)),
                    reinterpret_cast<const char*>(sqlite3_column_text(q, 1)), sqlite3_column_int(q, 2),
                    sqlite3_column_int64(q, 3), sqlite3_column_int64(q, 4)};
    losses[k] = sqlite3_column_type(q, 5) == SQLITE_NULL ? std::nan("") : sqlite3_column_double(q, 5);
  }
  sqlite3_finalize(q);
  sqlite3_close(db);
  return losses;
}

// a grid's episodes in a database file (table evals): how many, how many have a finite loss (stored
// non-NULL), and how many satisfy the SQL condition `which` (gd's gradients by default); -1 each
// when the file cannot be read
struct EpisodeCounts {
  long long episodes = -1, finite = -1, matching = -1;
};
inline EpisodeCounts episode_counts(const std::string& path, const std::string& which = "used_grad") {
  EpisodeCounts n;
  const std::string sql = "SELECT count(*), sum(loss IS NOT NULL), sum(" + which + ") FROM evals";
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK) << path;
  sqlite3_stmt* q = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr), SQLITE_OK) << sql;
  if (q && sqlite3_step(q) == SQLITE_ROW) {
    n.episodes = sqlite3_column_int64(q, 0);
    n.finite = sqlite3_column_int64(q, 1);
    n.matching = sqlite3_column_int64(q, 2);
  }
  sqlite3_finalize(q);
  sqlite3_close(db);
  return n;
}

// runs SQL that changes a database (a test's tampering with a copy)
inline void execute(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK) << path;
  sqlite3_busy_timeout(db, 10000);
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  EXPECT_EQ(rc, SQLITE_OK) << sql << ": " << (err ? err : "");
  sqlite3_free(err);
  sqlite3_close(db);
}

}  // namespace dsb::testing
