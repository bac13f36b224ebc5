#include "harness/store.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <stdexcept>

#include "common/config_hash.hpp"

namespace dsb {

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string RunKey::text() const {
  return env + "/" + optimizer + "/seed " + std::to_string(seed) + "/budget " + std::to_string(budget) +
         "/config " + env_config_hash + "," + opt_config_hash + "/version " + harness_version;
}

Store::Store(const std::string& path, Provenance provenance)
    : lock_(path), db_(path), provenance_(std::move(provenance)) {
  prepare_schema(db_);
}

std::set<RunKey> Store::done_keys() {
  std::lock_guard lock(mutex_);
  std::set<RunKey> keys;
  Statement q(db_.handle(),
              "SELECT env, optimizer, seed, budget, env_config_hash, opt_config_hash, harness_version FROM runs "
              "WHERE status='done'");
  while (q.step())
    keys.insert({q.column_text(0), q.column_text(1), static_cast<int>(q.column_int(2)),
                 q.column_int(3), q.column_text(4), q.column_text(5), q.column_text(6)});
  return keys;
}

RunStart Store::begin_run(const RunKey& key, std::uint64_t rng_seed, const nlohmann::json& env_config,
                          const nlohmann::json& opt_config) {
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  Statement cfg(db_.handle(), "INSERT OR IGNORE INTO configs(hash, kind, json) VALUES (?, ?, ?)");
  cfg.bind(1, key.env_config_hash).bind(2, std::string("env")).bind(3, canonical_json(env_config)).run();
  cfg.bind(1, key.opt_config_hash).bind(2, std::string("optimizer")).bind(3, canonical_json(opt_config)).run();

  RunStart start;
  // an earlier attempt of this run left 'running': keep what it committed (resume by replay)
  Statement find(db_.handle(),
                 "SELECT run_id, status FROM runs WHERE env=? AND optimizer=? AND seed=? AND budget=? AND "
                 "env_config_hash=? AND opt_config_hash=? AND harness_version=?");
  find.bind(1, key.env).bind(2, key.optimizer).bind(3, static_cast<std::int64_t>(key.seed)).bind(4, key.budget)
      .bind(5, key.env_config_hash).bind(6, key.opt_config_hash).bind(7, key.harness_version);
  const bool resumable = find.step() && find.column_text(1) == "running";
  if (resumable) {
    start.run_id = find.column_int(0);
    Statement n(db_.handle(), "SELECT count(*) FROM evals WHERE run_id=?");
    n.bind(1, start.run_id);
    n.step();
    start.committed_episodes = n.column_int(0);
    Statement j(db_.handle(), "SELECT seq, kind, input_hash, payload FROM replay WHERE run_id=? ORDER BY seq");
    j.bind(1, start.run_id);
    while (j.step()) {
      if (j.column_int(0) != static_cast<std::int64_t>(start.journal.size())) break;  // a gap: keep the prefix
      start.journal.push_back({static_cast<ReplayKind>(j.column_int(1)), static_cast<std::uint64_t>(j.column_int(2)),
                               replay_payload_from_bytes(j.column_blob(3))});
    }
    Statement host(db_.handle(), "UPDATE runs SET host=?, git_sha=? WHERE run_id=?");
    host.bind(1, provenance_.host).bind(2, provenance_.git_sha).bind(3, start.run_id).run();
    tx.commit();
    return start;
  }
  find.reset();

  char seed_hex[17];
  std::snprintf(seed_hex, sizeof seed_hex, "%016llx", static_cast<unsigned long long>(rng_seed));
  Statement up(db_.handle(), R"sql(
    INSERT INTO runs(env, optimizer, seed, budget, env_config_hash, opt_config_hash, rng_seed,
                     status, started_at, harness_version, git_sha, host)
    VALUES (?, ?, ?, ?, ?, ?, ?, 'running', ?, ?, ?, ?)
    ON CONFLICT(env, optimizer, seed, budget, env_config_hash, opt_config_hash, harness_version) DO UPDATE SET
      status='running', episodes=0, failed_episodes=0, best_loss=NULL, best_x=NULL, wall_s=NULL,
      error=NULL, diagnostics=NULL, started_at=excluded.started_at, finished_at=NULL,
      git_sha=excluded.git_sha, host=excluded.host
    RETURNING run_id)sql");
  up.bind(1, key.env).bind(2, key.optimizer).bind(3, static_cast<std::int64_t>(key.seed))
      .bind(4, key.budget).bind(5, key.env_config_hash).bind(6, key.opt_config_hash)
      .bind(7, std::string(seed_hex)).bind(8, utc_now()).bind(9, key.harness_version)
      .bind(10, provenance_.git_sha).bind(11, provenance_.host);
  if (!up.step()) throw StoreError("sqlite: no run_id returned");
  start.run_id = up.column_int(0);
  up.reset();
  // a failed earlier attempt starts over
  Statement del_evals(db_.handle(), "DELETE FROM evals WHERE run_id=?");
  del_evals.bind(1, start.run_id).run();
  Statement del_journal(db_.handle(), "DELETE FROM replay WHERE run_id=?");
  del_journal.bind(1, start.run_id).run();
  tx.commit();
  return start;
}

namespace {

void insert_evals(Database& db, std::int64_t run_id, std::span<const EvalRecord> evals) {
  Statement ins(db.handle(),
                "INSERT OR REPLACE INTO evals(run_id, episode, loss, best_loss, used_grad, wall_s, failed, metric) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
  for (const auto& e : evals) {
    ins.bind(1, run_id).bind(2, e.episode).bind(3, e.loss).bind(4, e.best_loss)
        .bind(5, static_cast<std::int64_t>(e.used_grad)).bind(6, e.wall_s)
        .bind(7, static_cast<std::int64_t>(std::isnan(e.loss))).bind(8, e.metric);
    ins.run();
  }
}

}  // namespace

void Store::append_progress(std::int64_t run_id, std::span<const EvalRecord> evals, std::int64_t first_seq,
                            const std::vector<ReplayEntry>& journal) {
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  insert_evals(db_, run_id, evals);
  Statement ins(db_.handle(),
                "INSERT OR REPLACE INTO replay(run_id, seq, kind, input_hash, payload) VALUES (?, ?, ?, ?, ?)");
  std::int64_t seq = first_seq;
  for (const auto& e : journal) {
    ins.bind(1, run_id).bind(2, seq++).bind(3, static_cast<std::int64_t>(e.kind))
        .bind(4, static_cast<std::int64_t>(e.input_hash)).bind_blob(5, replay_payload_bytes(e.payload));
    ins.run();
  }
  Statement upd(db_.handle(), "UPDATE runs SET episodes=(SELECT count(*) FROM evals WHERE run_id=?) WHERE run_id=?");
  upd.bind(1, run_id).bind(2, run_id).run();
  tx.commit();
}

void Store::reset_progress(std::int64_t run_id) {
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  Statement del_evals(db_.handle(), "DELETE FROM evals WHERE run_id=?");
  del_evals.bind(1, run_id).run();
  Statement del_journal(db_.handle(), "DELETE FROM replay WHERE run_id=?");
  del_journal.bind(1, run_id).run();
  Statement upd(db_.handle(), "UPDATE runs SET episodes=0 WHERE run_id=?");
  upd.bind(1, run_id).run();
  tx.commit();
}

void Store::finish_run(std::int64_t run_id, const RunResult& r) {
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  Statement del(db_.handle(), "DELETE FROM evals WHERE run_id=?");
  del.bind(1, run_id).run();
  insert_evals(db_, run_id, r.evals);
  // what only a resume needs goes with the run's end
  Statement del_journal(db_.handle(), "DELETE FROM replay WHERE run_id=?");
  del_journal.bind(1, run_id).run();
  Statement upd(db_.handle(), R"sql(
    UPDATE runs SET status=?, episodes=?, failed_episodes=?, best_loss=?, best_x=?, wall_s=?,
                    error=?, finished_at=?, diagnostics=? WHERE run_id=?)sql");
  upd.bind(1, r.status).bind(2, r.episodes).bind(3, r.failed_episodes).bind(4, r.best_loss);
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
  upd.bind(10, run_id);
  upd.run();
  tx.commit();
}

}  // namespace dsb
