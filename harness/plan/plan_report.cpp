#include "harness/plan/plan_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include <fmt/format.h>

#include "harness/core/output_path.hpp"
#include "harness/plan/run_order.hpp"

namespace dsb {
namespace {

// a Slurm array task's target length: long enough that start-up is nothing, short enough for
// common partition limits and for a lost node to cost little
constexpr double kShardTargetSeconds = 6.0 * 3600.0;

std::string family_of(const RunSpec& spec) {
  if (!spec.entry) return "external (gradient episodes; own time unknown)";
  const OptimizerEntry& e = *spec.entry;
  if (!e.costs.family.empty()) return e.costs.family;
  if (e.needs_gradient) return "gradient episodes";
  return "forward episodes";
}

struct Tally {
  std::int64_t runs = 0;
  double seconds = 0.0, longest = 0.0;
  std::set<std::string> names;
};

}  // namespace

void write_plan_runs_csv(const std::string& path, const GridPlan& plan, const CostModel& costs, bool share, int jobs) {
  const std::vector<double> cost = run_costs(plan, costs);
  std::vector<std::size_t> rank(plan.pending.size());
  const std::vector<std::size_t> order = run_order(plan.pending, cost, share, jobs);
  for (std::size_t r = 0; r < order.size(); ++r) rank[order[r]] = r;
  const std::vector<std::ptrdiff_t> lead =
      share ? share_leads(plan.pending) : std::vector<std::ptrdiff_t>(plan.pending.size(), -1);
  OutputFile file("--runs-csv", path, false);
  file.stream() << "env,optimizer,seed,budget,planned_s,source,start_rank,lead_seed\n";
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const PlannedRun& p = plan.pending[i];
    const bool measured = !plan.measured_wall_s.empty() && std::isfinite(plan.measured_wall_s[i]);
    const std::string lead_seed =
        lead[i] >= 0 ? std::to_string(plan.pending[static_cast<std::size_t>(lead[i])].spec.seed) : std::string();
    file.stream() << fmt::format("{},{},{},{},{:.6g},{},{},{}\n", p.spec.env, p.spec.optimizer, p.spec.seed,
                                 p.spec.budget, cost[i], measured ? "measured" : "model", rank[i], lead_seed);
  }
  file.commit();
}

void print_failed_runs(std::ostream& out, const GridPlan& plan, const std::map<RunKey, std::string>& failed) {
  std::vector<const PlannedRun*> runs;
  for (const auto& p : plan.pending)
    if (failed.count(p.key)) runs.push_back(&p);
  if (runs.empty()) return;
  out << fmt::format("  failed in the database: {} of these runs (a grid exits 3 while any fails; each runs again):\n",
                     runs.size());
  for (std::size_t i = 0; i < runs.size() && i < kFailedRunsShown; ++i)
    out << fmt::format("    {}: {}\n", runs[i]->key.text(), failed.at(runs[i]->key));
  if (runs.size() > kFailedRunsShown) out << fmt::format("    ... and {} more\n", runs.size() - kFailedRunsShown);
}

std::vector<double> run_costs(const GridPlan& plan, const CostModel& costs) {
  std::vector<double> c;
  c.reserve(plan.pending.size());
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const double share = plan.shared_share.empty() ? 0.0 : plan.shared_share[i];
    const double measured =
        plan.measured_wall_s.empty() ? std::numeric_limits<double>::quiet_NaN() : plan.measured_wall_s[i];
    // a group's done runs in the database measure it; the cost model estimates the rest
    c.push_back(std::isfinite(measured) ? measured * (1.0 - share) : costs.run_seconds(plan.pending[i], share));
  }
  return c;
}

std::vector<ShardCost> shard_costs(const GridPlan& plan, const std::vector<double>& cost, int shards, int jobs) {
  std::vector<ShardCost> s(static_cast<std::size_t>(std::max(1, shards)));
  // each shard's runs, in plan order, as its task plans them (its own --shard I/N grid)
  std::vector<std::vector<PlannedRun>> runs(s.size());
  std::vector<std::vector<double>> costs(s.size());
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const auto k = static_cast<std::size_t>(shard_of(plan.pending[i], static_cast<int>(s.size())));
    s[k].seconds += cost[i];
    s[k].longest_run = std::max(s[k].longest_run, cost[i]);
    runs[k].push_back(plan.pending[i]);
    costs[k].push_back(cost[i]);
  }
  for (std::size_t k = 0; k < s.size(); ++k) s[k].wall = runner_wall(runs[k], costs[k], true, jobs);
  return s;
}

void print_plan(std::ostream& out, const GridPlan& plan, const CostModel& costs, const PlanContext& ctx) {
  const std::vector<double> cost = run_costs(plan, costs);
  std::map<std::string, Tally> by_env, by_family;
  std::set<std::string> measured, hinted, other_build;
  double total = 0.0, longest = 0.0;
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const auto& p = plan.pending[i];
    for (Tally* t : {&by_env[p.spec.env], &by_family[family_of(p.spec)]}) {
      ++t->runs;
      t->seconds += cost[i];
      t->longest = std::max(t->longest, cost[i]);
      t->names.insert(p.spec.optimizer);
    }
    (costs.episode(p.spec).measured ? measured : hinted).insert(p.spec.env);
    if (!costs.episode(p.spec).measured && costs.measured_by_other_build(p.spec.env, p.key.env_config_hash))
      other_build.insert(p.spec.env);
    total += cost[i];
    longest = std::max(longest, cost[i]);
  }
  out << fmt::format("plan: {} runs in the grid; {} already done in {}; {} to run ({} episodes)\n", plan.runs,
                     plan.skipped, ctx.db, plan.pending.size(), plan.pending_episodes);
  if (plan.pending.empty()) return;
  out << fmt::format(
      "  episode costs: measured on this machine for {} of {} envs (cache {}){}\n", measured.size(),
      measured.size() + hinted.size(), costs.path(),
      hinted.empty() ? std::string()
                     : "; the others from their cost hints (forward and gradient episodes on the "
                       "2-core machine the project measures on): `harness calibrate " +
              ctx.grid_flags + "` measures them, one episode each" +
              (other_build.empty() ? std::string()
                                   : fmt::format(" ({} of them were measured by another build of the "
                                                 "harness: a calibration belongs to the binary that made it)",
                                                 other_build.size())));
  out << fmt::format("  {:<26} {:>6} {:>11} {:>12}\n", "env", "runs", "core-hours", "longest run");
  std::vector<std::pair<std::string, Tally>> envs(by_env.begin(), by_env.end());
  std::stable_sort(envs.begin(), envs.end(),
                   [](const auto& a, const auto& b) { return a.second.seconds > b.second.seconds; });
  for (const auto& [name, t] : envs)
    out << fmt::format("  {:<26} {:>6} {:>11.2f} {:>12}\n", name, t.runs, t.seconds / 3600.0,
                       human_duration(t.longest));
  out << fmt::format("  {:<26} {:>6} {:>11}  {}\n", "optimizer family", "runs", "core-hours", "optimizers");
  for (const auto& [name, t] : by_family) {
    std::string names;
    for (const auto& n : t.names) names += (names.empty() ? "" : ", ") + n;
    out << fmt::format("  {:<26} {:>6} {:>11.2f}  {}\n", name, t.runs, t.seconds / 3600.0, names);
  }
  // what sharing across seeds saves
  double unshared = 0.0, shared_episodes = 0.0;
  std::int64_t sharing_runs = 0;
  std::int64_t measured_runs = 0;
  for (std::size_t i = 0; i < plan.pending.size(); ++i) {
    const bool measured = !plan.measured_wall_s.empty() && std::isfinite(plan.measured_wall_s[i]);
    measured_runs += measured;
    unshared += measured ? plan.measured_wall_s[i] : costs.run_seconds(plan.pending[i]);
    const double share = plan.shared_share.empty() ? 0.0 : plan.shared_share[i];
    shared_episodes += share * static_cast<double>(plan.pending[i].spec.budget);
    sharing_runs += share > 0.0;
  }
  if (measured_runs > 0)
    out << fmt::format(
        "  {} runs costed from the median wall time of their group's done runs in {} (the same env, "
        "optimizer, budget and configs)\n",
        measured_runs, ctx.db);
  if (sharing_runs > 0)
    out << fmt::format(
        "  sharing across seeds: {} runs take about {:.0f} episodes from an earlier seed's run of "
        "their group (the episodes before the optimizer's first draw, replayed: at the replay's measured "
        "cost on cheap envs, else free), saving about {:.4g} of {:.4g} core-hours; --no-sharing simulates them\n",
        sharing_runs, shared_episodes, (unshared - total) / 3600.0, unshared / 3600.0);
  // wall: the runs laid out as the runner takes them (run_order.hpp): the work over the jobs, never
  // less than the longest run, more where followers wait for their lead
  const double wall = runner_wall(plan.pending, cost, ctx.share, ctx.jobs);
  out << fmt::format(
      "  total: about {:.4g} core-hours (with the GP optimizers' and RL learners' own time, roughly); "
      "with --jobs {} --threads {}: about {} wall (the longest run alone {})\n",
      total / 3600.0, ctx.jobs, ctx.threads, human_duration(wall), human_duration(longest));
  // array tasks of about kShardTargetSeconds each on average, or one per job when --jobs names a
  // cluster's cores
  const int shards = static_cast<int>(std::clamp<double>(
      std::max(std::ceil(total / kShardTargetSeconds), 1.0 * ctx.jobs), 1.0, static_cast<double>(plan.pending.size())));
  if (wall > 24.0 * 3600.0 || shards > 1) {
    // tasks differ (shard_costs): the largest, which `harness slurm` sets its time limit from, is
    // what to expect
    std::vector<double> task;
    for (const ShardCost& c : shard_costs(plan, cost, shards, 1)) task.push_back(c.wall);
    std::sort(task.begin(), task.end());
    out << fmt::format(
        "  on a Slurm cluster: harness slurm {} --shards {} --dir slurm-run && bash slurm-run/submit.sh "
        "({} array tasks on one core each, of {} (median) up to {}: cut by run-key hash, not by cost; "
        "docs/running.md, \"Running on a Slurm cluster\")\n",
        ctx.grid_flags, shards, shards, human_duration(task[task.size() / 2]), human_duration(task.back()));
  }
}

void print_stale_runs(std::ostream& out, const std::vector<StaleRuns>& stale) {
  if (stale.empty()) return;
  std::int64_t done = 0, unfinished = 0;
  for (const auto& s : stale) {
    done += s.done;
    unfinished += s.unfinished;
  }
  out << fmt::format(
      "  stale: {} stored runs of this grid's envs and optimizers ({} done, {} unfinished) were made by "
      "other results versions: never resumed or counted as done, left in the database as they are\n",
      done + unfinished, done, unfinished);
  for (const auto& s : stale)
    out << fmt::format("    {} / {}: {} done, {} unfinished: {}\n", s.env, s.optimizer, s.done, s.unfinished, s.reason);
}

std::set<std::pair<std::string, std::string>> grid_pairs(const std::vector<RunSpec>& grid) {
  std::set<std::pair<std::string, std::string>> pairs;
  for (const auto& spec : grid) pairs.emplace(spec.env, spec.optimizer);
  return pairs;
}

}  // namespace dsb
