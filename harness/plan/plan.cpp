#include "harness/plan/plan.hpp"

#include <algorithm>
#include <limits>

#include "common/rng.hpp"

namespace dsb {
int shard_of(const PlannedRun& run, int count, bool group_seeds) {
  // the seeds of a group that shares across seeds go to one shard, where they can share
  const RunKey& key = run.key;
  const bool grouped = group_seeds && run.spec.may_share_seeds();
  std::string text;
  for (const std::string& part : {key.env, key.optimizer, grouped ? std::string() : std::to_string(key.seed),
                                  std::to_string(key.budget), key.env_config_hash, key.opt_config_hash}) {
    text += part;
    text.push_back('\0');
  }
  std::uint64_t h = fnv1a64(text);
  return static_cast<int>(splitmix64(h) % static_cast<std::uint64_t>(count));
}

GridPlan plan_grid(const std::vector<RunSpec>& grid, const std::set<RunKey>& done, const std::string& harness_version,
                   Shard shard) {
  GridPlan plan;
  for (const auto& spec : grid) {
    PlannedRun run{spec,
                   RunKey{spec.env, spec.optimizer, spec.seed, spec.budget, spec.env_config->hash,
                          spec.opt_config->hash, harness_version, spec.versions}};
    if (shard.count > 1 && shard_of(run, shard.count, shard.group_seeds) != shard.index) continue;
    ++plan.runs;
    if (done.count(run.key)) {
      ++plan.skipped;
      continue;
    }
    plan.pending_episodes += spec.budget;
    plan.pending.push_back(std::move(run));
  }
  return plan;
}

std::vector<std::ptrdiff_t> share_leads(const std::vector<PlannedRun>& runs) {
  std::map<std::string, std::size_t> lead_of;  // group -> index of its smallest seed
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!runs[i].spec.may_share_seeds() || runs[i].donor_stored) continue;
    const auto [it, added] = lead_of.emplace(runs[i].key.group(), i);
    if (!added && runs[i].spec.seed < runs[it->second].spec.seed) it->second = i;
  }
  std::vector<std::ptrdiff_t> lead(runs.size(), -1);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!runs[i].spec.may_share_seeds() || runs[i].donor_stored) continue;
    const std::size_t l = lead_of.at(runs[i].key.group());
    if (l != i) lead[i] = static_cast<std::ptrdiff_t>(l);
  }
  return lead;
}

void estimate_sharing(GridPlan& plan, const std::map<std::string, std::int64_t>& kept) {
  for (PlannedRun& p : plan.pending) p.donor_stored = p.spec.may_share_seeds() && kept.count(p.key.group()) > 0;
  const std::vector<std::ptrdiff_t> lead = share_leads(plan.pending);
  plan.shared_share.assign(plan.pending.size(), 0.0);
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const PlannedRun& p = plan.pending[i];
    if (!p.spec.may_share_seeds()) continue;
    const auto k = kept.find(p.key.group());
    if (k != kept.end())
      plan.shared_share[i] = std::min(1.0, static_cast<double>(k->second) / static_cast<double>(p.spec.budget));
    else if (lead[i] >= 0)
      plan.shared_share[i] = p.spec.entry->typical_seed_free_share;
  }
}

void use_measured_walls(GridPlan& plan, const std::map<std::string, double>& walls) {
  plan.measured_wall_s.assign(plan.pending.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < plan.pending.size(); ++i)
    if (const auto w = walls.find(plan.pending[i].key.group()); w != walls.end()) plan.measured_wall_s[i] = w->second;
}

}  // namespace dsb
