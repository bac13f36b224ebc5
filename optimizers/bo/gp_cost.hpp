#pragma once
// The GP optimizers' own seconds per run, for `harness plan` (optimizers/core/optimizer_costs.hpp),
// on one core of the reference machine (docs/performance.md "Performance").
#include <cstdint>

#include "optimizers/bo/bo.hpp"

namespace dsb {

// bo: its fits follow BoConfig's schedule (after every point up to refit_every_until, then at
// every refit_growth of growth); a fit evaluates the likelihood kBoEvaluationsPerFit times (L-BFGS
// from fit_attempts starts), each a Cholesky factorization and an inverse, O(n^3), and gradients
// O(n^2 d). Seconds = evaluations x (kBoSecondsPerN3 n^3 + kBoSecondsPerN2D n^2 d) summed over the
// fits, which also covers the acquisitions between them. The two per-evaluation constants were
// fitted (least squares in log) to what six 1,000-episode runs spent beyond their first 200
// episodes (bo and boleap on sphere-10, rastrigin-10 and cartpole1, seed 0, commit 94a4ca2, this
// 2-core machine on 2026-11-28: bo 96-98 s in 10-D and 352 s in 200-D, boleap 47-75 s and 343 s);
// the model gives 0.63-1.97x of each. The earlier constants (1.09e-9, 1.7e-9, from 300-episode
// runs) put the n^3 term 6x too high: they overestimated those six 1.6-6x. How many evaluations a
// fit takes depends on the loss (a smooth one takes more): the model is a typical run's, within a
// factor of about 2; a database's own done runs make `harness plan` exact (measured walls).
inline constexpr double kBoEvaluationsPerFit = 80.0;
inline constexpr double kBoSecondsPerN3 = 1.78e-10;
inline constexpr double kBoSecondsPerN2D = 2.97e-9;
double bo_own_seconds(int dim, std::int64_t budget, const BoConfig& cfg = {});
// the fits of that schedule over a run (a run's diagnostics count the same as gp_fits)
int bo_fits(int dim, std::int64_t budget, const BoConfig& cfg = {});

// boleap: its GP is fitted on the initial design and then at the end of every leap of
// `episodes_per_leap` episodes that leaves budget for another (n = n0, n0 + E, n0 + 2E, ... < budget),
// each fit at the same per-evaluation costs as bo's; a fit takes more likelihood evaluations as n
// grows: kBoLeapEvaluationsBase + kBoLeapEvaluationsPerPoint n (fitted to the runs' diagnostics:
// 172-196 evaluations over the 2 fits of 200-episode runs (n 11-20, 110-120), 1,277-1,876 over the
// 11 fits of 1,000-episode runs on cartpole1 and rastrigin-10).
inline constexpr double kBoLeapEvaluationsBase = 70.0;
inline constexpr double kBoLeapEvaluationsPerPoint = 0.17;
double boleap_own_seconds(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg = {});
// the fits of that schedule over a run
int boleap_fits(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg = {});

}  // namespace dsb
