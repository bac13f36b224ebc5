#include "harness/plan/run_order.hpp"

#include <algorithm>
#include <functional>
#include <numeric>
#include <queue>

namespace dsb {

std::vector<std::size_t> cheapest_first(const std::vector<double>& run_cost_s) {
  std::vector<std::size_t> order(run_cost_s.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return run_cost_s[a] < run_cost_s[b]; });
  return order;
}

std::vector<std::size_t> run_order(const std::vector<PlannedRun>& pending, const std::vector<double>& run_cost_s,
                                   bool share, int jobs) {
  if (!share) return cheapest_first(run_cost_s);
  const std::vector<std::ptrdiff_t> lead = share_leads(pending);
  if (std::all_of(lead.begin(), lead.end(), [](std::ptrdiff_t l) { return l < 0; })) return cheapest_first(run_cost_s);
  // a group goes by its lead's cost: a follower that replays most of its episodes is cheap, but it
  // cannot start before the lead has ended
  std::vector<double> group_cost = run_cost_s;
  for (std::size_t i = 0; i < pending.size(); ++i)
    if (lead[i] >= 0) group_cost[i] = run_cost_s[static_cast<std::size_t>(lead[i])];
  const std::vector<std::size_t> cheap = cheapest_first(group_cost);

  // the planned start of each run: in that order on `jobs` workers, each run on the worker free first
  std::vector<double> start(pending.size(), 0.0);
  std::priority_queue<double, std::vector<double>, std::greater<>> free_at;
  for (int w = 0; w < std::max(1, jobs); ++w) free_at.push(0.0);
  for (const std::size_t i : cheap) {
    const double t = free_at.top();
    free_at.pop();
    start[i] = t;
    free_at.push(t + std::max(0.0, run_cost_s[i]));
  }
  // a lead starts its own length before the first of its followers is due (never later than its own slot)
  std::vector<double> key = start;
  for (std::size_t i = 0; i < pending.size(); ++i)
    if (lead[i] >= 0) {
      const auto l = static_cast<std::size_t>(lead[i]);
      key[l] = std::min(key[l], start[i] - std::max(0.0, run_cost_s[l]));
    }
  // by that key; ties (and equal starts) keep the cheapest-first order
  std::vector<std::size_t> rank(pending.size());
  for (std::size_t r = 0; r < cheap.size(); ++r) rank[cheap[r]] = r;
  std::vector<std::size_t> order = cheap;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return key[a] != key[b] ? key[a] < key[b] : rank[a] < rank[b];
  });
  return order;
}

std::vector<double> runner_end_times(const std::vector<std::size_t>& order, const std::vector<double>& run_cost_s,
                                     const std::vector<std::ptrdiff_t>& lead, int jobs) {
  std::vector<double> end(run_cost_s.size(), -1.0);
  std::vector<char> taken(run_cost_s.size(), 0), ended(run_cost_s.size(), 0);
  // the runs in progress by their end (ties by index, so the schedule is a function of its inputs)
  using Running = std::pair<double, std::size_t>;
  std::priority_queue<Running, std::vector<Running>, std::greater<>> running;
  int free_workers = std::max(1, jobs);
  double now = 0.0;
  for (;;) {
    // each free worker takes the first open run in order
    for (std::size_t r = 0; free_workers > 0 && r < order.size(); ++r) {
      const std::size_t i = order[r];
      if (taken[i] || (lead[i] >= 0 && !ended[static_cast<std::size_t>(lead[i])])) continue;
      taken[i] = 1;
      end[i] = now + std::max(0.0, run_cost_s[i]);
      running.emplace(end[i], i);
      --free_workers;
    }
    if (running.empty()) return end;
    // the next run to end frees its worker
    now = running.top().first;
    ended[running.top().second] = 1;
    running.pop();
    ++free_workers;
  }
}

double runner_wall(const std::vector<PlannedRun>& pending, const std::vector<double>& run_cost_s, bool share,
                   int jobs) {
  const std::vector<std::ptrdiff_t> lead =
      share ? share_leads(pending) : std::vector<std::ptrdiff_t>(pending.size(), -1);
  const std::vector<double> end = runner_end_times(run_order(pending, run_cost_s, share, jobs), run_cost_s, lead, jobs);
  return end.empty() ? 0.0 : *std::max_element(end.begin(), end.end());
}

}  // namespace dsb
