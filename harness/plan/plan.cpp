#include "harness/plan/plan.hpp"

#include <algorithm>
#include <limits>

#include "common/config_hash.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
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

std::vector<std::ptrdiff_t> share_leads(const std::vector<PlannedRun>& runs) {
  std::map<std::string, std::size_t> lead_of;  // group -> index of its smallest seed
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!may_share_seeds(runs[i].spec)) continue;
    const auto [it, added] = lead_of.emplace(runs[i].key.group(), i);
    if (!added && runs[i].spec.seed < runs[it->second].spec.seed) it->second = i;
  }
  std::vector<std::ptrdiff_t> lead(runs.size(), -1);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!may_share_seeds(runs[i].spec)) continue;
    const std::size_t l = lead_of.at(runs[i].key.group());
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
    const auto k = kept.find(p.key.group());
    if (k != kept.end())
      plan.shared_share[i] = std::min(1.0, static_cast<double>(k->second) / static_cast<double>(p.spec.budget));
    else if (lead[i] >= 0)
      plan.shared_share[i] = optimizer_entry(p.spec.optimizer).typical_seed_free_share;
  }
}

void use_measured_walls(GridPlan& plan, const std::map<std::string, double>& walls) {
  plan.measured_wall_s.assign(plan.pending.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < plan.pending.size(); ++i)
    if (const auto w = walls.find(plan.pending[i].key.group()); w != walls.end())
      plan.measured_wall_s[i] = w->second;
}

}  // namespace dsb
