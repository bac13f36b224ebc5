#include "harness/store/merge.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "harness/core/run_status.hpp"
#include "harness/store/run_key_sql.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/tables.hpp"

namespace dsb {
namespace {

// A run row is every column of runs but run_id, an eval row every column of evals but run_id, a
// journal row every column of replay (or prefix) but run_id, in schema order (tables.hpp). A file
// of an older version reads a column it lacks, or a run key column it leaves NULL, as its default
// (read_column): harness_version '' (NULL in files before schema version 3), the sharing columns
// what a run without sharing has (before 4), results_versions '' (before 5: made before versions,
// stale for every binary that has them; kept apart from the runs of any version).
const int kRunColumnCount = static_cast<int>(runs_table().columns.size()) - 1;
const int kEvalColumnCount = static_cast<int>(evals_table().columns.size()) - 1;
const int kJournalColumnCount = static_cast<int>(replay_table().columns.size()) - 1;

// the position of a column in a run row or an eval row
std::size_t run_at(const char* column) {
  return static_cast<std::size_t>(column_index(runs_table(), column, "run_id"));
}
std::size_t eval_at(const char* column) {
  return static_cast<std::size_t>(column_index(evals_table(), column, "run_id"));
}

// a SQLite value as read: NULL, integer, real, text or blob, compared and written back exactly
struct Cell {
  int type = 0;  // SQLITE_NULL 5, SQLITE_INTEGER 1, SQLITE_FLOAT 2, SQLITE_TEXT 3, SQLITE_BLOB 4
  std::int64_t i = 0;
  double d = 0.0;
  std::string s;
  bool operator==(const Cell& o) const {
    if (type != o.type) return false;
    if (type == 1) return i == o.i;
    if (type == 2) return std::bit_cast<std::uint64_t>(d) == std::bit_cast<std::uint64_t>(o.d);
    return s == o.s;
  }
};

using Row = std::vector<Cell>;

Row read_row(Statement& q, int n) {
  Row row(static_cast<std::size_t>(n));
  for (int c = 0; c < n; ++c) {
    Cell& cell = row[static_cast<std::size_t>(c)];
    cell.type = q.column_type(c);
    if (cell.type == 1) cell.i = q.column_int(c);
    if (cell.type == 2) cell.d = q.column_double(c);
    if (cell.type == 3) cell.s = q.column_text(c);
    if (cell.type == 4) cell.s = q.column_blob(c);
  }
  return row;
}

void bind_row(Statement& st, const Row& row, int first_index) {
  for (std::size_t c = 0; c < row.size(); ++c) {
    const int index = first_index + static_cast<int>(c);
    const Cell& cell = row[c];
    if (cell.type == 1)
      st.bind(index, cell.i);
    else if (cell.type == 2)
      st.bind(index, cell.d);
    else if (cell.type == 3)
      st.bind(index, cell.s);
    else if (cell.type == 4)
      st.bind_blob(index, cell.s);
    else
      st.bind_null(index);
  }
}

struct RunRecord {
  Row run;                   // a run row
  std::vector<Row> evals;    // eval rows, by episode
  std::vector<Row> journal;  // journal rows (running runs)
  std::vector<Row> prefix;   // the same, of a done run's kept seed-free episodes
  const Cell& at(const char* column) const { return run[run_at(column)]; }
  RunStatus status() const { return stored_status(at("status").s).value_or(RunStatus::running); }
  std::int64_t committed() const { return static_cast<std::int64_t>(evals.size()); }
  RunKey key() const {
    return {at("env").s,
            at("optimizer").s,
            static_cast<int>(at("seed").i),
            at("budget").i,
            at("env_config_hash").s,
            at("opt_config_hash").s,
            at("harness_version").s,
            stored_results_versions(at("results_versions").s)};
  }
};

// the columns of an eval row that are its result: all but its wall time
bool same_eval(const Row& a, const Row& b) {
  for (const char* c : {"episode", "loss", "best_loss", "used_grad", "failed", "metric"})
    if (!(a[eval_at(c)] == b[eval_at(c)])) return false;
  return true;
}

RunRecord read_run(Database& db, std::int64_t run_id, int version) {
  RunRecord r;
  Statement q(db.handle(), "SELECT " + read_columns(runs_table(), version, "run_id") + " FROM runs WHERE run_id=?");
  q.bind(1, run_id);
  if (q.step()) r.run = read_row(q, kRunColumnCount);
  Statement e(
      db.handle(),
      "SELECT " + read_columns(evals_table(), version, "run_id") + " FROM evals WHERE run_id=? ORDER BY episode");
  e.bind(1, run_id);
  while (e.step()) r.evals.push_back(read_row(e, kEvalColumnCount));
  for (const auto& [table, rows] : {std::pair{&replay_table(), &r.journal}, std::pair{&prefix_table(), &r.prefix}}) {
    if (version < table->since) continue;
    Statement j(
        db.handle(),
        "SELECT " + read_columns(*table, version, "run_id") + " FROM " + table->name + " WHERE run_id=? ORDER BY seq");
    j.bind(1, run_id);
    while (j.step()) rows->push_back(read_row(j, kJournalColumnCount));
  }
  return r;
}

// what two records of one run key must share to be the same result: every episode's loss,
// best-so-far, gradient use, failure flag and metric (not its wall time), and the run's status,
// episode counts, best loss and best point
bool same_result(const RunRecord& a, const RunRecord& b) {
  for (const char* c : {"status", "episodes", "failed_episodes", "best_loss", "best_x"})
    if (!(a.at(c) == b.at(c))) return false;
  if (a.evals.size() != b.evals.size()) return false;
  for (std::size_t k = 0; k < a.evals.size(); ++k)
    if (!same_eval(a.evals[k], b.evals[k])) return false;
  return true;
}

// the id of the run with this key in `db`, if any
std::optional<std::int64_t> find_run(Database& db, const RunKey& k) {
  Statement q(db.handle(), "SELECT run_id FROM runs WHERE " + run_key_match());
  bind_run_key(q, 1, k);
  if (!q.step()) return std::nullopt;
  return q.column_int(0);
}

void delete_run(Database& db, std::int64_t run_id) {
  for (const char* sql : {"DELETE FROM evals WHERE run_id=?", "DELETE FROM replay WHERE run_id=?",
                          "DELETE FROM prefix WHERE run_id=?", "DELETE FROM runs WHERE run_id=?"}) {
    Statement st(db.handle(), sql);
    st.bind(1, run_id).run();
  }
}

void insert_run(Database& db, const RunRecord& r) {
  const Table& runs = runs_table();
  Statement run(db.handle(),
                "INSERT INTO runs(" + column_names(runs, kSchemaVersion, "run_id") + ") VALUES (" +
                    placeholders(kRunColumnCount) + ") RETURNING run_id");
  bind_row(run, r.run, 1);
  if (!run.step()) throw StoreError("merge: no run_id returned");
  const std::int64_t id = run.column_int(0);
  run.reset();
  // the rows of the run's other tables, each under the new run_id
  for (const auto& [table, rows] : {std::pair{&evals_table(), &r.evals}, std::pair{&replay_table(), &r.journal},
                                    std::pair{&prefix_table(), &r.prefix}}) {
    const int n = static_cast<int>(table->columns.size());
    Statement ins(db.handle(),
                  "INSERT INTO " + std::string(table->name) + "(" + column_names(*table, kSchemaVersion) +
                      ") VALUES (" + placeholders(n) + ")");
    for (const auto& row : *rows) {
      ins.bind(1, id);
      bind_row(ins, row, 2);
      ins.run();
    }
  }
}

// Two copies of one run key hold the same result where both have it: over the episodes both
// committed, every loss, best-so-far, gradient use, failure flag and metric agree (wall times
// aside). A shorter copy is an earlier point of the same run (interrupted, or failed by an
// external cause such as a timeout); copies that differ there are different results.
bool consistent(const RunRecord& a, const RunRecord& b) {
  const std::size_t n = std::min(a.evals.size(), b.evals.size());
  for (std::size_t k = 0; k < n; ++k)
    if (!same_eval(a.evals[k], b.evals[k])) return false;
  return true;
}

// rank of a status: done > failed > running
int rank(RunStatus status) { return status == RunStatus::done ? 2 : status == RunStatus::failed ? 1 : 0; }

// every stored byte of a copy, in a fixed order: the last tiebreak between copies, so that which
// copy survives never depends on the order of the inputs
std::string content_of(const RunRecord& r) {
  std::string bytes;
  const auto add = [&](const Row& row) {
    for (const Cell& c : row) {
      bytes += static_cast<char>(c.type);
      if (c.type == 1) bytes += std::to_string(c.i);
      if (c.type == 2) bytes += std::to_string(std::bit_cast<std::uint64_t>(c.d));
      if (c.type == 3 || c.type == 4) bytes += c.s;
      bytes += '\0';
    }
  };
  add(r.run);
  for (const Row& e : r.evals) add(e);
  for (const Row& j : r.journal) add(j);
  for (const Row& p : r.prefix) add(p);
  return bytes;
}

// the copy to keep: the further status, then more committed episodes, then the smaller content
bool better(const RunRecord& a, const RunRecord& b) {
  if (rank(a.status()) != rank(b.status())) return rank(a.status()) > rank(b.status());
  if (a.committed() != b.committed()) return a.committed() > b.committed();
  return content_of(a) < content_of(b);
}

// A StoreError while reading an input is that input's fault: exit 2 naming it.
template <class F>
auto reading(const std::string& input, F&& f) {
  try {
    return f();
  } catch (const StoreError& e) {
    throw UsageError("merge: input '" + input + "': " + e.what());
  }
}

}  // namespace

// Every input is a harness database whose runs' configs are all there, checked before the
// output is opened: a foreign or broken file changes nothing.
void check_merge_input(const std::string& in, const std::string& into) {
  namespace fs = std::filesystem;
  std::error_code ec;
  check_database_path("merge input", in, true);  // missing, a folder, a FIFO: refused before it is opened
  if (fs::exists(into) && fs::equivalent(in, into, ec))
    throw UsageError("merge: input '" + in + "' is the output itself");
  reading(in, [&] {
    Database db(in, Database::Mode::read_only);
    if (check_schema(db) == 0) throw StoreError("it has no harness tables");
    Statement q(db.handle(),
                "SELECT env, optimizer, seed, CASE WHEN env_config_hash NOT IN (SELECT hash FROM configs) THEN "
                "env_config_hash ELSE opt_config_hash END FROM runs WHERE env_config_hash NOT IN (SELECT hash FROM "
                "configs) OR opt_config_hash NOT IN (SELECT hash FROM configs) ORDER BY run_id LIMIT 1");
    if (q.step())
      throw StoreError("run " + q.column_text(0) + "/" + q.column_text(1) + "/seed " + std::to_string(q.column_int(2)) +
                       " names config " + q.column_text(3) + ", which its configs table lacks");
    return 0;
  });
}

// the output's new files, removed when a merge that created them is refused
void remove_database_files(const std::string& path) {
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::remove((path + suffix).c_str());
}

MergeCounts merge_inputs(Store& store, const std::vector<std::string>& inputs) {
  Database& out = store.db();
  MergeCounts n;
  std::map<RunKey, std::string> source;  // the input each merged run came from, for conflicts
  Transaction tx(out);                   // all inputs or nothing
  for (const auto& in : inputs) {
    reading(in, [&] {
      Database db(in, Database::Mode::read_only);
      const int version = check_schema(db);
      const Table& configs = configs_table();
      const std::string config_columns = column_names(configs, version);
      const int n_config = static_cast<int>(configs.columns.size());
      Statement cfg(db.handle(), "SELECT " + config_columns + " FROM configs");
      Statement put(out.handle(),
                    "INSERT OR IGNORE INTO configs(" + config_columns + ") VALUES (" + placeholders(n_config) + ")");
      while (cfg.step()) {
        bind_row(put, read_row(cfg, n_config), 1);
        put.run();
      }

      std::vector<std::int64_t> ids;
      Statement all(db.handle(), "SELECT run_id FROM runs ORDER BY run_id");
      while (all.step()) ids.push_back(all.column_int(0));
      for (const std::int64_t id : ids) {
        RunRecord theirs = read_run(db, id, version);
        if (theirs.status() != RunStatus::running) theirs.journal.clear();  // only an unfinished run resumes
        if (theirs.status() != RunStatus::done) theirs.prefix.clear();      // only a done run keeps a prefix
        const RunKey key = theirs.key();
        const auto existing = find_run(out, key);
        if (!existing) {
          insert_run(out, theirs);
          source[key] = in;
          ++n.added;
          continue;
        }
        const RunRecord ours = read_run(out, *existing, kSchemaVersion);
        const std::string other = source.count(key) ? "'" + source[key] + "'" : "the output";
        const bool both_done = theirs.status() == RunStatus::done && ours.status() == RunStatus::done;
        if (!consistent(theirs, ours) || (both_done && !same_result(theirs, ours)))
          throw UsageError("merge: run " + key.text() + " in '" + in + "' conflicts with its copy from " + other +
                           " (same key, different evals); nothing was written");
        if (better(theirs, ours)) {
          delete_run(out, *existing);
          insert_run(out, theirs);
          source[key] = in;
          ++n.replaced;
        } else {
          ++(both_done ? n.identical : n.kept);
        }
      }
      return 0;
    });
  }
  tx.commit();
  return n;
}

}  // namespace dsb
