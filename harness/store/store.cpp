#include "harness/store/store.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <stdexcept>

#include <unistd.h>

#include "common/config_hash.hpp"
#include "common/shown_value.hpp"
#include "harness/store/run_key_sql.hpp"
#include "harness/store/tables.hpp"

namespace dsb {

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

Store::Store(const std::string& path, Provenance provenance)
    : path_(path), lock_(path), db_(path), provenance_(std::move(provenance)) {
  prepare_schema(db_);
}

void Store::check_path() {
  std::lock_guard lock(mutex_);
  refuse_if_moved();
}

void Store::refuse_if_moved() {
  if (lock_.names_locked_file(path_)) return;
  // What this process committed may still sit in the write-ahead log, which keeps the old name:
  // a checkpoint through the open descriptors copies it into the file itself, wherever it is now.
  bool complete = false;
  try {
    Statement cp(db_.handle(), "PRAGMA wal_checkpoint(TRUNCATE)");
    complete = cp.step() && cp.column_int(0) == 0;  // busy = 0: every frame copied
  } catch (const StoreError&) {}
  const std::string now = lock_.current_path();
  const std::string was = "database '" + shown_value(path_) + "' was ";
  if (!now.empty() && complete)
    throw StoreError(was + "moved or replaced while this harness wrote it: everything it committed is in '" +
                     shown_value(now) + "' (the file it opened), and it stopped writing; resume with --db '" +
                     shown_value(now) + "'");
  // deleted, or the log could not be emptied: a complete copy beside the old name, made now
  const std::string rescue = path_ + ".rescued-" + std::to_string(::getpid()) + ".sqlite";
  try {
    Statement copy(db_.handle(), "VACUUM INTO ?");
    copy.bind(1, rescue).run();
  } catch (const StoreError& e) {
    throw StoreError(was + (now.empty() ? "deleted" : "moved or replaced") +
                     " while this harness wrote it, and it stopped writing; a copy of what it committed could not be "
                     "made (" +
                     e.what() + ")");
  }
  throw StoreError(was + (now.empty() ? "deleted" : "moved or replaced") +
                   " while this harness wrote it, and it stopped writing: a copy of everything it committed is in '" +
                   shown_value(rescue) + "'; resume with --db naming it");
}

std::set<RunKey> Store::done_keys() {
  std::lock_guard lock(mutex_);
  std::set<RunKey> keys;
  Statement q(db_.handle(), "SELECT " + run_key_columns(kSchemaVersion) + " FROM runs WHERE status='done'");
  while (q.step()) keys.insert(read_run_key(q, 0));
  return keys;
}

namespace {

// the columns of a journal row (replay and prefix alike) but run_id: seq, kind, input_hash, payload
std::string journal_columns() { return column_names(replay_table(), kSchemaVersion, "run_id"); }

// the first `calls` entries of a run's journal in `table` (replay or prefix), up to a gap
std::vector<ReplayEntry> read_journal(Database& db, const std::string& table, std::int64_t run_id, std::int64_t calls) {
  std::vector<ReplayEntry> journal;
  Statement j(db.handle(), "SELECT " + journal_columns() + " FROM " + table + " WHERE run_id=? AND seq<? ORDER BY seq");
  j.bind(1, run_id).bind(2, calls);
  while (j.step()) {
    if (j.column_int(0) != static_cast<std::int64_t>(journal.size())) break;  // a gap: keep the prefix
    journal.push_back({static_cast<ReplayKind>(j.column_int(1)), static_cast<std::uint64_t>(j.column_int(2)),
                       replay_payload_from_bytes(j.column_blob(3))});
  }
  return journal;
}

// The longest seed-free prefix another seed's run of the group holds: a done run's kept prefix,
// or what a running one committed (all of it while its optimizer has not drawn). Ties go to the
// smallest seed. Nothing (episodes 0) when there is none.
struct Donor {
  std::int64_t run_id = 0, episodes = 0, calls = 0;
  int seed = -1;
  std::string table;
};

Donor find_donor(Database& db, const RunKey& key) {
  Donor best;
  Statement q(db.handle(),
              std::string("SELECT run_id, seed, status, seed_free_episodes, seed_free_calls, "
                          "(SELECT count(*) FROM evals e WHERE e.run_id=r.run_id), "
                          "(SELECT count(*) FROM replay j WHERE j.run_id=r.run_id), "
                          "(SELECT count(*) FROM prefix p WHERE p.run_id=r.run_id) "
                          "FROM runs r WHERE ") +
                  run_key_match(false) + " AND seed<>? AND status IN ('done', 'running') ORDER BY seed");
  bind_run_key(q, 1, key, false);
  q.bind(8, static_cast<std::int64_t>(key.seed));
  while (q.step()) {
    Donor d{q.column_int(0), 0, 0, static_cast<int>(q.column_int(1)), ""};
    const bool known = !q.column_is_null(3);
    if (q.column_text(2) == "done") {
      if (!known || q.column_int(7) < q.column_int(4)) continue;  // no kept prefix
      d.episodes = q.column_int(3);
      d.calls = q.column_int(4);
      d.table = "prefix";
    } else {
      const bool drew_before = known && q.column_int(3) <= q.column_int(5);
      d.episodes = drew_before ? q.column_int(3) : q.column_int(5);
      d.calls = drew_before ? q.column_int(4) : q.column_int(6);
      d.table = "replay";
    }
    if (d.episodes > best.episodes) best = d;
  }
  return best;
}

// The run row a start writes: its key, its seed, 'running', when and where it started (13
// parameters: the key's 8, then rng_seed, status, started_at, git_sha, host). A row an earlier
// attempt left (failed, or done and redone) is taken over: those columns are written and every
// other column of runs goes back to its default (NULL where it has none).
std::string start_run_sql() {
  const Table& runs = runs_table();
  const std::vector<std::string> written = {"rng_seed", "status", "started_at", "git_sha", "host"};
  const auto key = unique_key_columns(runs, kSchemaVersion);
  std::string set;
  for (const Column* c : columns_at(runs, kSchemaVersion)) {
    const std::string name = c->name;
    if (name == "run_id" || std::find(key.begin(), key.end(), name) != key.end()) continue;
    const bool given = std::find(written.begin(), written.end(), name) != written.end();
    set += (set.empty() ? "" : ", ") + name + "=" + (given ? "excluded." + name : default_value(*c));
  }
  std::string columns = unique_key(runs, kSchemaVersion);
  for (const auto& c : written) columns += ", " + c;
  return "INSERT INTO runs(" + columns + ") VALUES (" + placeholders(static_cast<int>(key.size() + written.size())) +
      ") ON CONFLICT(" + unique_key(runs, kSchemaVersion) + ") DO UPDATE SET " + set + " RETURNING run_id";
}

}  // namespace

RunStart Store::begin_run(const RunKey& key, std::uint64_t rng_seed, const nlohmann::json& env_config,
                          const nlohmann::json& opt_config, bool share) {
  std::lock_guard lock(mutex_);
  refuse_if_moved();  // before a commit: the path must still name the file this store opened
  Transaction tx(db_);
  Statement cfg(db_.handle(),
                "INSERT OR IGNORE INTO configs(" + column_names(configs_table(), kSchemaVersion) + ") VALUES (" +
                    placeholders(3) + ")");
  cfg.bind(1, key.env_config_hash).bind(2, std::string("env")).bind(3, canonical_json(env_config)).run();
  cfg.bind(1, key.opt_config_hash).bind(2, std::string("optimizer")).bind(3, canonical_json(opt_config)).run();

  RunStart start;
  // an earlier attempt of this run left 'running': keep what it committed (resume by replay)
  Statement find(db_.handle(), "SELECT run_id, status FROM runs WHERE " + run_key_match());
  bind_run_key(find, 1, key);
  const bool resumable = find.step() && find.column_text(1) == "running";
  if (resumable) {
    start.run_id = find.column_int(0);
    Statement n(db_.handle(), "SELECT count(*) FROM evals WHERE run_id=?");
    n.bind(1, start.run_id);
    n.step();
    start.committed_episodes = n.column_int(0);
    start.journal = read_journal(db_, "replay", start.run_id, std::numeric_limits<std::int64_t>::max());
    start.journal_episodes = start.committed_episodes;
    Statement shared(db_.handle(),
                     "SELECT shared_episodes, COALESCE(shared_from_seed, -1), cpu_s FROM runs WHERE run_id=?");
    shared.bind(1, start.run_id);
    if (shared.step()) {
      start.shared_episodes = shared.column_int(0);
      start.shared_from_seed = static_cast<int>(shared.column_int(1));
      // what its earlier sessions spent: unknown when they committed episodes without saying
      start.cpu_s = !shared.column_is_null(2) ? shared.column_double(2)
          : start.committed_episodes == 0     ? 0.0
                                              : std::numeric_limits<double>::quiet_NaN();
    }
    Statement host(db_.handle(), "UPDATE runs SET host=?, git_sha=? WHERE run_id=?");
    host.bind(1, provenance_.host).bind(2, provenance_.git_sha).bind(3, start.run_id).run();
    tx.commit();
    return start;
  }
  find.reset();

  char seed_hex[17];
  std::snprintf(seed_hex, sizeof seed_hex, "%016llx", static_cast<unsigned long long>(rng_seed));
  Statement up(db_.handle(), start_run_sql());
  bind_run_key(up, 1, key);
  up.bind(9, std::string(seed_hex))
      .bind(10, std::string(stored_text(RunStatus::running)))
      .bind(11, utc_now())
      .bind(12, provenance_.git_sha)
      .bind(13, provenance_.host);
  if (!up.step()) throw StoreError("sqlite: no run_id returned");
  start.run_id = up.column_int(0);
  up.reset();
  // a failed earlier attempt starts over
  Statement del_evals(db_.handle(), "DELETE FROM evals WHERE run_id=?");
  del_evals.bind(1, start.run_id).run();
  Statement del_journal(db_.handle(), "DELETE FROM replay WHERE run_id=?");
  del_journal.bind(1, start.run_id).run();
  if (share) {
    // the seed-free prefix of another seed's run, copied into this run's journal (so that an
    // interruption resumes from it as from the run's own) and replayed
    const Donor donor = find_donor(db_, key);
    if (donor.episodes > 0) {
      start.journal = read_journal(db_, donor.table, donor.run_id, donor.calls);
      if (static_cast<std::int64_t>(start.journal.size()) == donor.calls) {
        Statement copy(db_.handle(),
                       "INSERT INTO replay(run_id, " + journal_columns() + ") SELECT ?, " + journal_columns() +
                           " FROM " + donor.table + " WHERE run_id=? AND seq<?");
        copy.bind(1, start.run_id).bind(2, donor.run_id).bind(3, donor.calls).run();
        Statement mark(db_.handle(), "UPDATE runs SET shared_episodes=?, shared_from_seed=? WHERE run_id=?");
        mark.bind(1, donor.episodes).bind(2, static_cast<std::int64_t>(donor.seed)).bind(3, start.run_id).run();
        start.journal_episodes = start.shared_episodes = donor.episodes;
        start.shared_from_seed = donor.seed;
      } else {
        start.journal.clear();  // a prefix with a gap is not used
      }
    }
  }
  tx.commit();
  return start;
}

namespace {

void insert_evals(Database& db, std::int64_t run_id, std::span<const EvalRecord> evals) {
  // an eval row: every column of evals, in schema order
  Statement ins(db.handle(),
                "INSERT OR REPLACE INTO evals(" + column_names(evals_table(), kSchemaVersion) + ") VALUES (" +
                    placeholders(8) + ")");
  for (const auto& e : evals) {
    ins.bind(1, run_id)
        .bind(2, e.episode)
        .bind(3, e.loss)
        .bind(4, e.best_loss)
        .bind(5, static_cast<std::int64_t>(e.used_grad))
        .bind(6, e.wall_s)
        .bind(7, static_cast<std::int64_t>(std::isnan(e.loss)))
        .bind(8, e.metric);
    ins.run();
  }
}

// Journal entries as rows of `table` (replay or prefix), the first at seq `first_seq`, up to seq
// `end_seq` (exclusive).
void insert_journal(Database& db, const std::string& table, std::int64_t run_id, std::int64_t first_seq,
                    const std::vector<ReplayEntry>& entries, std::int64_t end_seq) {
  Statement ins(db.handle(),
                "INSERT OR REPLACE INTO " + table + "(" + column_names(replay_table(), kSchemaVersion) + ") VALUES (" +
                    placeholders(5) + ")");
  std::int64_t seq = first_seq;
  for (const auto& e : entries) {
    if (seq >= end_seq) break;
    ins.bind(1, run_id)
        .bind(2, seq++)
        .bind(3, static_cast<std::int64_t>(e.kind))
        .bind(4, static_cast<std::int64_t>(e.input_hash))
        .bind_blob(5, replay_payload_bytes(e.payload));
    ins.run();
  }
}

}  // namespace

void Store::append_progress(std::int64_t run_id, std::span<const EvalRecord> evals, std::int64_t first_seq,
                            const std::vector<ReplayEntry>& journal, const SeedFreePrefix& seed_free, double cpu_s) {
  std::lock_guard lock(mutex_);
  refuse_if_moved();  // before a commit: the path must still name the file this store opened
  Transaction tx(db_);
  insert_evals(db_, run_id, evals);
  insert_journal(db_, "replay", run_id, first_seq, journal, std::numeric_limits<std::int64_t>::max());
  Statement upd(db_.handle(),
                "UPDATE runs SET episodes=(SELECT count(*) FROM evals WHERE run_id=?), cpu_s=? WHERE run_id=?");
  upd.bind(1, run_id);
  upd.bind(2, cpu_s);  // NaN: NULL
  upd.bind(3, run_id).run();
  if (seed_free.drew) {
    Statement mark(db_.handle(), "UPDATE runs SET seed_free_episodes=?, seed_free_calls=? WHERE run_id=?");
    mark.bind(1, seed_free.episodes).bind(2, seed_free.calls).bind(3, run_id).run();
  }
  tx.commit();
}

void Store::reset_progress(std::int64_t run_id) {
  std::lock_guard lock(mutex_);
  refuse_if_moved();  // before a commit: the path must still name the file this store opened
  Transaction tx(db_);
  Statement del_evals(db_.handle(), "DELETE FROM evals WHERE run_id=?");
  del_evals.bind(1, run_id).run();
  Statement del_journal(db_.handle(), "DELETE FROM replay WHERE run_id=?");
  del_journal.bind(1, run_id).run();
  Statement upd(db_.handle(),
                "UPDATE runs SET episodes=0, seed_free_episodes=NULL, seed_free_calls=NULL, shared_episodes=0, "
                "shared_from_seed=NULL WHERE run_id=?");
  upd.bind(1, run_id).run();
  tx.commit();
}

void Store::keep_seed_free_prefix(std::int64_t run_id, const RunResult& r) {
  const std::int64_t calls = r.seed_free.calls;
  if (r.seed_free.episodes <= 0 || calls <= 0) return;
  // the other done runs of the group that keep a prefix
  const std::string others =
      "SELECT o.run_id FROM runs o JOIN runs me ON me.run_id=? AND o.run_id<>me.run_id AND o.env=me.env AND "
      "o.optimizer=me.optimizer AND o.budget=me.budget AND o.env_config_hash=me.env_config_hash AND "
      "o.opt_config_hash=me.opt_config_hash AND o.harness_version=me.harness_version AND "
      "o.results_versions=me.results_versions AND o.status='done' "
      "WHERE EXISTS (SELECT 1 FROM prefix p WHERE p.run_id=o.run_id)";
  Statement longest(db_.handle(),
                    "SELECT COALESCE(max(seed_free_calls), 0) FROM runs WHERE run_id IN (" + others + ")");
  longest.bind(1, run_id);
  if (longest.step() && longest.column_int(0) >= calls) return;
  // the committed journal's entries of the prefix, then those not committed yet
  const std::string columns = column_names(replay_table(), kSchemaVersion);
  Statement copy(
      db_.handle(),
      "INSERT OR REPLACE INTO prefix(" + columns + ") SELECT " + columns + " FROM replay WHERE run_id=? AND seq<?");
  copy.bind(1, run_id).bind(2, calls).run();
  insert_journal(db_, "prefix", run_id, r.journal_tail_first_seq, r.journal_tail, calls);
  Statement count(db_.handle(), "SELECT count(*) FROM prefix WHERE run_id=?");
  count.bind(1, run_id);
  count.step();
  const bool whole = count.column_int(0) == calls;
  count.reset();
  // a prefix with a gap (a journal lost to an older harness) is not kept; a whole one replaces
  // the group's shorter ones
  Statement drop(
      db_.handle(),
      whole ? "DELETE FROM prefix WHERE run_id IN (" + others + ")" : std::string("DELETE FROM prefix WHERE run_id=?"));
  drop.bind(1, run_id).run();
}

void Store::finish_run(std::int64_t run_id, const RunResult& r) {
  std::lock_guard lock(mutex_);
  refuse_if_moved();  // before a commit: the path must still name the file this store opened
  Transaction tx(db_);
  Statement del(db_.handle(), "DELETE FROM evals WHERE run_id=?");
  del.bind(1, run_id).run();
  insert_evals(db_, run_id, r.evals);
  if (r.status != RunStatus::done && r.status != RunStatus::failed)
    throw std::logic_error("finish_run: a run ends done or failed");
  if (r.status == RunStatus::done) keep_seed_free_prefix(run_id, r);
  // what only a resume needs goes with the run's end
  Statement del_journal(db_.handle(), "DELETE FROM replay WHERE run_id=?");
  del_journal.bind(1, run_id).run();
  Statement upd(db_.handle(), R"sql(
    UPDATE runs SET status=?, episodes=?, failed_episodes=?, best_loss=?, best_x=?, wall_s=?,
                    error=?, finished_at=?, diagnostics=?, seed_free_episodes=?, seed_free_calls=?, cpu_s=?
                WHERE run_id=?)sql");
  upd.bind(1, std::string(stored_text(r.status))).bind(2, r.episodes).bind(3, r.failed_episodes).bind(4, r.best_loss);
  if (r.best_x.empty())
    upd.bind_null(5);
  else
    upd.bind(5, nlohmann::json(r.best_x).dump());
  upd.bind(6, r.wall_s);
  if (r.error.empty())
    upd.bind_null(7);
  else
    upd.bind(7, r.error);
  upd.bind(8, utc_now());
  if (r.diagnostics.is_null())
    upd.bind_null(9);
  else
    upd.bind(9, r.diagnostics.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  upd.bind(10, r.seed_free.episodes).bind(11, r.seed_free.calls);
  upd.bind(12, r.cpu_s);
  upd.bind(13, run_id);
  upd.run();
  tx.commit();
}

}  // namespace dsb
