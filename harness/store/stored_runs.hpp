#pragma once
// What a command reads of the runs a results file already holds, before it plans a grid: the keys
// of its done runs, its runs of a status with their errors, the seed-free prefixes it keeps for
// other seeds, its done runs' wall times, and its stale runs. Read-only queries over a database
// the command opened once (the Store of a grid run, or StoredRunsFile for `harness plan`).
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "harness/core/results_versions.hpp"
#include "harness/core/run_key.hpp"

namespace dsb {

class Database;

class StoredRuns {
 public:
  // the runs of an open harness database (its schema version read once); null: no database, so
  // every answer is empty
  explicit StoredRuns(Database* db);

  // the keys of its 'done' runs
  std::set<RunKey> done_keys() const;
  // its runs with this status ('done', 'failed'), each with its error (empty when it has none)
  std::map<RunKey, std::string> with_status(const std::string& status) const;
  // the seed-free episodes that its done runs keep for other seeds, by RunKey::group (nothing in a
  // file from before sharing)
  std::map<std::string, std::int64_t> kept_prefixes() const;
  // the median wall seconds of its done runs by RunKey::group, of the runs that simulated every
  // episode (none shared: a shared run's wall is not what its group costs)
  std::map<std::string, double> measured_walls() const;
  // its runs whose results versions are not this binary's, by env, optimizer and reason, of the
  // (env, optimizer) pairs given (all when empty)
  std::vector<StaleRuns> stale(const std::set<std::pair<std::string, std::string>>& pairs = {}) const;

 private:
  Database* db_;
  int version_ = 0;  // schema version; 0: no database, or one without tables
};

// A results file opened read-only, once, by a command that writes nothing (`harness plan`): its
// runs, or none when the file does not exist. Throws StoreError naming the file when it is not a
// harness database or is newer than this harness.
class StoredRunsFile {
 public:
  explicit StoredRunsFile(const std::string& path);
  ~StoredRunsFile();
  const StoredRuns& runs() const { return runs_; }

 private:
  std::unique_ptr<Database> db_;
  StoredRuns runs_;
};

}  // namespace dsb
