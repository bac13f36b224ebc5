#include "harness/plan.hpp"

#include <algorithm>
#include <filesystem>
#include <limits>

#include "common/config_hash.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "harness/grid.hpp"
#include "harness/schema.hpp"
#include "harness/sqlite_db.hpp"
#include "optimizers/registry.hpp"

namespace dsb {
namespace {

template <class ConfigOf>
const ResolvedConfig& resolve(std::map<std::string, ResolvedConfig>& cache, const std::string& name,
                              ConfigOf&& config_of) {
  auto it = cache.find(name);
  if (it == cache.end()) {
    nlohmann::json c = config_of(name);
    std::string h = config_hash(c);
    it = cache.emplace(name, ResolvedConfig{std::move(c), std::move(h)}).first;
  }
  return it->second;
}

}  // namespace

int shard_of(const RunKey& key, int count, bool group_seeds) {
  // the seeds of a group that shares across seeds go to one shard, where they can share
  const bool grouped = group_seeds && key.optimizer.rfind("ext:", 0) != 0 &&
                       optimizer_entry(key.optimizer).seed_use != SeedUse::at_start;
  std::string text;
  for (const std::string& part : {key.env, key.optimizer, grouped ? std::string() : std::to_string(key.seed),
                                  std::to_string(key.budget), key.env_config_hash, key.opt_config_hash}) {
    text += part;
    text.push_back('\0');
  }
  std::uint64_t h = fnv1a64(text);
  return static_cast<int>(splitmix64(h) % static_cast<std::uint64_t>(count));
}

namespace {

// the runs' results_versions column as SQL: '' in a file from before versions (schema 4 or older)
std::string versions_sql(int schema_version) { return schema_version >= 5 ? "results_versions" : "''"; }

}  // namespace

GridPlan plan_grid(const std::vector<RunSpec>& grid, const std::set<RunKey>& done,
                   const std::string& harness_version, Shard shard) {
  GridPlan plan;
  for (const auto& spec : grid) {
    const ResolvedConfig& env =
        resolve(plan.env_configs, spec.env,
                [&](const std::string& n) { return shared_env(n, spec.env_options)->config(); });
    const ResolvedConfig& opt =
        resolve(plan.opt_configs, spec.optimizer, [&](const std::string&) { return make_run_optimizer(spec)->config(); });
    RunKey key{spec.env,  spec.optimizer, spec.seed,      spec.budget,
               env.hash,  opt.hash,       harness_version, current_results_versions(spec.env, spec.optimizer)};
    if (shard.count > 1 && shard_of(key, shard.count, shard.group_seeds) != shard.index) continue;
    ++plan.runs;
    if (done.count(key)) {
      ++plan.skipped;
      continue;
    }
    plan.pending_episodes += spec.budget;
    plan.pending.push_back({spec, std::move(key), &env, &opt});
  }
  return plan;
}

bool may_share_seeds(const RunSpec& spec) {
  return !spec.ext && optimizer_entry(spec.optimizer).seed_use != SeedUse::at_start;
}

std::string seed_group_of(const RunKey& key) {
  std::string g;
  for (const std::string& part : {key.env, key.optimizer, std::to_string(key.budget), key.env_config_hash,
                                  key.opt_config_hash, key.harness_version, key.versions.text()}) {
    g += part;
    g.push_back('\0');
  }
  return g;
}

std::vector<std::ptrdiff_t> share_leads(const std::vector<PlannedRun>& runs) {
  std::map<std::string, std::size_t> lead_of;  // group -> index of its smallest seed
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!may_share_seeds(runs[i].spec)) continue;
    const auto [it, added] = lead_of.emplace(seed_group_of(runs[i].key), i);
    if (!added && runs[i].spec.seed < runs[it->second].spec.seed) it->second = i;
  }
  std::vector<std::ptrdiff_t> lead(runs.size(), -1);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!may_share_seeds(runs[i].spec)) continue;
    const std::size_t l = lead_of.at(seed_group_of(runs[i].key));
    if (l != i) lead[i] = static_cast<std::ptrdiff_t>(l);
  }
  return lead;
}

void estimate_sharing(GridPlan& plan, const std::map<std::string, std::int64_t>& kept) {
  const std::vector<std::ptrdiff_t> lead = share_leads(plan.pending);
  plan.shared_share.assign(plan.pending.size(), 0.0);
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const PlannedRun& p = plan.pending[i];
    if (!may_share_seeds(p.spec)) continue;
    const auto k = kept.find(seed_group_of(p.key));
    if (k != kept.end())
      plan.shared_share[i] = std::min(1.0, static_cast<double>(k->second) / static_cast<double>(p.spec.budget));
    else if (lead[i] >= 0)
      plan.shared_share[i] = optimizer_entry(p.spec.optimizer).typical_seed_free_share;
  }
}

void use_measured_walls(GridPlan& plan, const std::map<std::string, double>& walls) {
  plan.measured_wall_s.assign(plan.pending.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < plan.pending.size(); ++i)
    if (const auto w = walls.find(seed_group_of(plan.pending[i].key)); w != walls.end())
      plan.measured_wall_s[i] = w->second;
}

std::map<std::string, double> measured_walls_of_file(const std::string& path) {
  std::map<std::string, std::vector<double>> by_group;
  if (!std::filesystem::exists(path)) return {};
  Database db(path, Database::Mode::read_only);
  const int version = check_schema(db);
  if (version == 0) return {};
  Statement q(db.handle(), std::string("SELECT env, optimizer, seed, budget, env_config_hash, opt_config_hash, "
                                       "harness_version, wall_s, ") +
                               versions_sql(version) + " FROM runs WHERE status='done' AND wall_s > 0" +
                               (version >= 4 ? " AND shared_episodes = 0" : ""));
  while (q.step()) {
    const RunKey key{q.column_text(0), q.column_text(1), static_cast<int>(q.column_int(2)), q.column_int(3),
                     q.column_text(4), q.column_text(5), q.column_text(6), stored_results_versions(q.column_text(8))};
    by_group[seed_group_of(key)].push_back(q.column_double(7));
  }
  std::map<std::string, double> walls;
  for (auto& [group, w] : by_group) {
    std::sort(w.begin(), w.end());
    const std::size_t m = w.size() / 2;
    walls[group] = w.size() % 2 ? w[m] : 0.5 * (w[m - 1] + w[m]);
  }
  return walls;
}

std::map<std::string, std::int64_t> kept_prefixes_of_file(const std::string& path) {
  std::map<std::string, std::int64_t> kept;
  if (!std::filesystem::exists(path)) return kept;
  Database db(path, Database::Mode::read_only);
  const int version = check_schema(db);
  if (version < 4) return kept;
  Statement q(db.handle(),
              "SELECT env, optimizer, seed, budget, env_config_hash, opt_config_hash, harness_version, "
              "seed_free_episodes, " + versions_sql(version) +
                  " FROM runs r WHERE status='done' AND seed_free_episodes > 0 AND EXISTS (SELECT 1 "
                  "FROM prefix p WHERE p.run_id=r.run_id)");
  while (q.step()) {
    const RunKey key{q.column_text(0), q.column_text(1), static_cast<int>(q.column_int(2)), q.column_int(3),
                     q.column_text(4), q.column_text(5), q.column_text(6), stored_results_versions(q.column_text(8))};
    std::int64_t& e = kept[seed_group_of(key)];
    e = std::max(e, q.column_int(7));
  }
  return kept;
}

std::map<RunKey, std::string> runs_of_file(const std::string& path, const std::string& status) {
  std::map<RunKey, std::string> runs;
  if (!std::filesystem::exists(path)) return runs;
  Database db(path, Database::Mode::read_only);
  const int version = check_schema(db);  // refuses a file that is not a harness database
  if (version == 0) return runs;
  Statement q(db.handle(),
              "SELECT env, optimizer, seed, budget, env_config_hash, opt_config_hash, harness_version, "
              "COALESCE(error, ''), " + versions_sql(version) + " FROM runs WHERE status=?");
  q.bind(1, status);
  while (q.step())
    runs.emplace(RunKey{q.column_text(0), q.column_text(1), static_cast<int>(q.column_int(2)), q.column_int(3),
                        q.column_text(4), q.column_text(5), q.column_text(6), stored_results_versions(q.column_text(8))},
                 q.column_text(7));
  return runs;
}

std::set<RunKey> done_keys_of_file(const std::string& path) {
  std::set<RunKey> keys;
  for (auto& [key, error] : runs_of_file(path, "done")) keys.insert(key);
  return keys;
}


std::vector<StaleRuns> stale_runs_of_file(const std::string& path,
                                          const std::set<std::pair<std::string, std::string>>& pairs) {
  std::map<std::string, StaleRuns> by_reason;
  if (!std::filesystem::exists(path)) return {};
  Database db(path, Database::Mode::read_only);
  const int version = check_schema(db);
  if (version == 0) return {};
  Statement q(db.handle(), "SELECT env, optimizer, " + versions_sql(version) +
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

}  // namespace dsb
