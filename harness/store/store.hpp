#pragma once
// The results database (schema: harness/store/schema.hpp, docs/database.md "Database"): runs, evals, configs, meta,
// replay. WAL mode, one writer: a Store holds an exclusive lock on the file itself (harness/
// file_lock.hpp: a flock every path to the file meets, released by the kernel when the process
// ends, however it ends), so a second harness on the same file is refused with a message naming
// the first. Opening refuses a foreign or newer
// file and migrates an older one. A run row is inserted as 'running' when it starts; its episodes
// and their journal (harness/core/replay.hpp) are committed as it goes (append_progress), and its
// final status when it ends, so a killed harness leaves no run that counts as done and loses at
// most the episodes since the last commit.
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <vector>
#include <string>

#include <nlohmann/json.hpp>

#include "harness/store/file_lock.hpp"
#include "harness/core/replay.hpp"
#include "harness/core/results_versions.hpp"
#include "harness/core/run_key.hpp"
#include "harness/core/run_spec.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/stored_runs.hpp"

namespace dsb {

// where a run starts: its row, and what an interrupted earlier attempt committed, or the
// seed-free prefix it takes from another seed's run
struct RunStart {
  std::int64_t run_id = 0;
  std::int64_t committed_episodes = 0;  // evals already in the database
  std::vector<ReplayEntry> journal;     // to replay them (or the shared prefix)
  std::int64_t journal_episodes = 0;    // the episodes the journal regenerates
  std::int64_t shared_episodes = 0;     // of them, taken from the run of seed shared_from_seed
  int shared_from_seed = -1;
  double cpu_s = 0.0;  // the CPU seconds its earlier sessions spent (runs.cpu_s; NaN: unknown)
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
  // what the file holds, read over this store's connection (before the grid starts: not locked)
  StoredRuns runs() { return StoredRuns(&db_); }

  // Records the configs and marks the run 'running' (inserting or reusing its row). A run left
  // 'running' by an interrupted harness keeps its committed episodes and returns them with their
  // journal; a 'failed' one starts again from nothing. With `share`, a run that starts from
  // nothing takes the longest seed-free prefix of a done or running run of another seed of the
  // same env, optimizer, budget, configs and version (sharing across seeds): its journal is
  // copied into this run's and returned to be replayed, and the run row says from which seed.
  RunStart begin_run(const RunKey& key, std::uint64_t rng_seed, const nlohmann::json& env_config,
                     const nlohmann::json& opt_config, bool share = false);

  // Commits a running run's new episodes (episode numbers from evals[0].episode on) and journal
  // entries (call indices from first_seq on) in one transaction, with its seed-free prefix once
  // the optimizer has drawn (while it has not, all it committed is seed-free) and the CPU seconds
  // it has spent so far over its sessions (NaN: unknown, stored NULL).
  void append_progress(std::int64_t run_id, std::span<const EvalRecord> evals, std::int64_t first_seq,
                       const std::vector<ReplayEntry>& journal, const SeedFreePrefix& seed_free = {},
                       double cpu_s = std::numeric_limits<double>::quiet_NaN());

  // Forgets a running run's committed episodes, journal and sharing (a replay that diverged
  // starts over).
  void reset_progress(std::int64_t run_id);

  // Replaces the run's evals, sets its final status, diagnostics and seed-free prefix, and drops
  // its journal, in one transaction. A done run keeps the journal of its seed-free episodes (in
  // `prefix`, with result.journal_tail, the entries not committed yet) when no other done run of
  // its group keeps as long a one; shorter ones of the group are dropped.
  void finish_run(std::int64_t run_id, const RunResult& result);

  Database& db() { return db_; }

  // Throws StoreError when the path no longer names the file this store opened (moved, replaced
  // or deleted while it ran; device and inode compared). Every write checks it first, so nothing
  // is committed to a file the path no longer names; a grid checks once more at its end. The
  // message says where the committed data is: the moved file (after a checkpoint that empties the
  // write-ahead log, which keeps the old name), or a copy made beside the old name.
  void check_path();

 private:
  void keep_seed_free_prefix(std::int64_t run_id, const RunResult& result);
  void refuse_if_moved();  // check_path, with mutex_ held

  std::string path_;
  FileLock lock_;
  Database db_;
  Provenance provenance_;
  std::mutex mutex_;
};

// UTC timestamp, ISO 8601
std::string utc_now();

}  // namespace dsb
