#pragma once
// The results database (schema of design.md and harness/schema.hpp): runs, evals, configs, meta.
// WAL mode, one writer. Opening refuses a foreign or newer file and migrates an older one.
// A run row is inserted as 'running' when it starts; its evals and final status are committed
// together in one transaction when it ends, so a killed harness leaves no run that counts as done.
#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <tuple>

#include <nlohmann/json.hpp>

#include "harness/run_spec.hpp"
#include "harness/schema.hpp"
#include "harness/sqlite_db.hpp"

namespace dsb {

// the UNIQUE key of a run
struct RunKey {
  std::string env, optimizer;
  int seed;
  std::int64_t budget;
  std::string env_config_hash, opt_config_hash;
  auto tie() const { return std::tie(env, optimizer, seed, budget, env_config_hash, opt_config_hash); }
  bool operator<(const RunKey& o) const { return tie() < o.tie(); }
};

struct Provenance {
  std::string harness_version, git_sha, host;
};

class Store {
 public:
  // Opens or creates the database and brings it to kSchemaVersion (prepare_schema: a foreign or
  // newer file is refused before anything is written, an older one migrated). Throws StoreError.
  Store(const std::string& path, Provenance provenance);

  // keys of runs whose status is 'done'
  std::set<RunKey> done_keys();

  // Records the configs and marks the run 'running' (inserting or reusing its row); returns run_id.
  std::int64_t begin_run(const RunKey& key, std::uint64_t rng_seed, const nlohmann::json& env_config,
                         const nlohmann::json& opt_config);

  // Replaces the run's evals and sets its final status and diagnostics, in one transaction.
  void finish_run(std::int64_t run_id, const RunResult& result);

  Database& db() { return db_; }

 private:
  Database db_;
  Provenance provenance_;
  std::mutex mutex_;
};

// UTC timestamp, ISO 8601
std::string utc_now();

}  // namespace dsb
