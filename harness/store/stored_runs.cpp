#include "harness/store/stored_runs.hpp"

#include <algorithm>
#include <filesystem>

#include "harness/store/run_key_sql.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/tables.hpp"

namespace dsb {
namespace {

// a results file that does not exist yet reads as none: every answer empty
std::unique_ptr<Database> open_if_there(const std::string& path) {
  if (!std::filesystem::exists(path)) return nullptr;
  return std::make_unique<Database>(path, Database::Mode::read_only);
}

}  // namespace

StoredRuns::StoredRuns(Database* db) : db_(db), version_(db ? check_schema(*db) : 0) {}

std::set<RunKey> StoredRuns::done_keys() const {
  std::set<RunKey> keys;
  for (auto& [key, error] : with_status("done")) keys.insert(key);
  return keys;
}

std::map<RunKey, std::string> StoredRuns::with_status(const std::string& status) const {
  std::map<RunKey, std::string> runs;
  if (version_ == 0) return runs;
  Statement q(db_->handle(), "SELECT " + run_key_columns(version_) + ", COALESCE(error, '') FROM runs WHERE status=?");
  q.bind(1, status);
  while (q.step()) runs.emplace(read_run_key(q, 0), q.column_text(8));
  return runs;
}

std::map<std::string, std::int64_t> StoredRuns::kept_prefixes() const {
  std::map<std::string, std::int64_t> kept;
  if (version_ < 4) return kept;
  Statement q(db_->handle(),
              "SELECT " + run_key_columns(version_) +
                  ", seed_free_episodes FROM runs r WHERE status='done' AND seed_free_episodes > 0 AND "
                  "EXISTS (SELECT 1 FROM prefix p WHERE p.run_id=r.run_id)");
  while (q.step()) {
    std::int64_t& e = kept[read_run_key(q, 0).group()];
    e = std::max(e, q.column_int(8));
  }
  return kept;
}

std::map<std::string, double> StoredRuns::measured_walls() const {
  std::map<std::string, std::vector<double>> by_group;
  if (version_ == 0) return {};
  Statement q(db_->handle(),
              "SELECT " + run_key_columns(version_) + ", wall_s FROM runs WHERE status='done' AND wall_s > 0" +
                  (version_ >= 4 ? " AND shared_episodes = 0" : ""));
  while (q.step()) by_group[read_run_key(q, 0).group()].push_back(q.column_double(8));
  std::map<std::string, double> walls;
  for (auto& [group, w] : by_group) {
    std::sort(w.begin(), w.end());
    const std::size_t m = w.size() / 2;
    walls[group] = w.size() % 2 ? w[m] : 0.5 * (w[m - 1] + w[m]);
  }
  return walls;
}

std::vector<StaleRuns> StoredRuns::stale(const std::set<std::pair<std::string, std::string>>& pairs) const {
  std::map<std::string, StaleRuns> by_reason;
  if (version_ == 0) return {};
  Statement q(db_->handle(),
              std::string("SELECT env, optimizer, ") + read_column(runs_table(), "results_versions", version_) +
                  ", status, count(*) FROM runs GROUP BY 1, 2, 3, 4 ORDER BY 1, 2, 3, 4");
  while (q.step()) {
    const std::string env = q.column_text(0), optimizer = q.column_text(1);
    if (!pairs.empty() && !pairs.count({env, optimizer})) continue;
    const std::string why = stale_reason(env, optimizer, stored_results_versions(q.column_text(2)));
    if (why.empty()) continue;
    StaleRuns& s = by_reason[env + "\n" + optimizer + "\n" + why];
    s.env = env;
    s.optimizer = optimizer;
    s.reason = why;
    (q.column_text(3) == "done" ? s.done : s.unfinished) += q.column_int(4);
  }
  std::vector<StaleRuns> out;
  for (auto& [k, s] : by_reason) out.push_back(std::move(s));
  return out;
}

StoredRunsFile::StoredRunsFile(const std::string& path) : db_(open_if_there(path)), runs_(db_.get()) {}

StoredRunsFile::~StoredRunsFile() = default;

}  // namespace dsb
