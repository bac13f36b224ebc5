#pragma once
// The order a grid's pending runs start in, and the wall they take in it. Results never depend on
// the order (every run is a function of its key); what depends on it is when partial reports fill
// and whether cores wait.
#include <cstddef>
#include <vector>

#include "harness/plan/plan.hpp"

namespace dsb {

// cheapest first (stable, so equal costs keep grid order), so partial reports come early
std::vector<std::size_t> cheapest_first(const std::vector<double>& run_cost_s);

// With sharing across seeds (share_leads), the runner starts a follower only after its lead has
// ended. Cheapest first alone would reach an expensive group's lead only when its followers are
// also due, and cores would wait for it at the end of the grid. So the order is a list schedule:
// the runs are laid on `jobs` workers cheapest first, a sharing group by its lead's cost (each run
// starting when the earliest worker is free), and each lead is then pulled earlier by its own
// estimated seconds, so that it ends about when its group's followers are due. Light envs still
// come first and report early; an expensive lead runs beside them a little ahead of its
// followers. On the full grid's plan (docs/running.md) this keeps cheapest first's early
// reports and leads first's end. Without sharing (or without leads): cheapest first.
std::vector<std::size_t> run_order(const std::vector<PlannedRun>& pending, const std::vector<double>& run_cost_s,
                                   bool share, int jobs);

// The runner's rule (harness/run/runner.hpp) on estimated costs: `jobs` workers; a free worker takes
// the first run in `order` not taken whose lead (`lead`: share_leads, -1 for none) has ended, and
// when every open run waits for a lead it waits for a run to end. Each run's end in seconds from the
// grid's start, indexed as `cost` (-1 for a run that never starts: its lead is not in `order`).
std::vector<double> runner_end_times(const std::vector<std::size_t>& order, const std::vector<double>& run_cost_s,
                                     const std::vector<std::ptrdiff_t>& lead, int jobs);

// The wall the pending runs take as `harness` with these `jobs` runs them (run_order, then the
// runner's rule): at least the work over the workers and the longest run, and more where a sharing
// group's followers wait for their lead (a 5-seed group of lead L and followers F on 4 cores: L + F,
// not (L + 4 F) / 4).
double runner_wall(const std::vector<PlannedRun>& pending, const std::vector<double>& run_cost_s, bool share, int jobs);

}  // namespace dsb
