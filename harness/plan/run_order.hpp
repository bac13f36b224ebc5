#pragma once
// The order a grid's pending runs start in. Results never depend on it (every run is a function of
// its key); what depends on it is when partial reports fill and whether cores wait.
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

}  // namespace dsb
