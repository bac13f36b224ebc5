#pragma once
// The GP optimizers' own seconds per run, for `harness plan` (optimizers/core/optimizer_costs.hpp),
// on one core of the reference machine (docs/performance.md "Performance").
#include <cstdint>

#include "optimizers/bo/bo.hpp"

namespace dsb {

// bo: its fits follow BoConfig's schedule (after every point up to refit_every_until, then at
// every refit_growth of growth); a fit evaluates the likelihood kBoEvaluationsPerFit times (L-BFGS
// from fit_attempts starts), each a Cholesky factorization and an inverse, O(n^3), and gradients
// O(n^2 d). Fit seconds = evaluations x (kBoSecondsPerN3 n^3 + kBoSecondsPerN2D n^2 d) summed over
// the fits. Between fits, every episode after the initial design is one LCB minimization
// (bo_acquisition_seconds): lcb_evaluations(cfg.lcb) posterior evaluations at the n points so far,
// each a kernel vector, O(n d), and the variance's triangular solve, O(n^2); seconds =
// kBoSecondsPerLcbTerm x evaluations x n (n + d) summed over the episodes. In 10-D the
// acquisitions are about two thirds of a 1,000-episode run's own time (a profile of sphere-10:
// the posterior's matrix-vector products, solves and exponentials against the fits' matrix
// products), so a model of the fits alone put bo at 0.55-0.64x what it took, and boleap, which
// proposes once per leap, at 1.3-2.3x. The three constants are fitted (scripts/gp-cost-fit.sh:
// least squares in log) to what six runs spent beyond their first 200 episodes (bo and boleap on
// sphere-10, rastrigin-10 and cartpole1, seed 0, 1,000 against 200 episodes, commit f935bfe on
// this 2-core machine, 2026-11-29: bo 96-160 s, boleap 38-97 s); the model gives 0.75-1.32x of
// each (boleap's two 10-D runs, 38 and 68 s, bracket its one figure). How many evaluations a fit
// takes depends on the loss (a smooth one takes more): the model is a typical run's, within a
// factor of about 2; a database's own done runs make `harness plan` exact (measured walls).
inline constexpr double kBoEvaluationsPerFit = 80.0;
inline constexpr double kBoSecondsPerN3 = 1.14e-10;
inline constexpr double kBoSecondsPerN2D = 4.13e-10;
inline constexpr double kBoSecondsPerLcbTerm = 2.53e-10;
double bo_own_seconds(int dim, std::int64_t budget, const BoConfig& cfg = {});
// the acquisitions' part of bo_own_seconds
double bo_acquisition_seconds(int dim, std::int64_t budget, const BoConfig& cfg = {});
// posterior evaluations of one LCB minimization at most: raw samples, then L-BFGS restarts
int lcb_evaluations(const LcbConfig& cfg);
// the fits of that schedule over a run (a run's diagnostics count the same as gp_fits)
int bo_fits(int dim, std::int64_t budget, const BoConfig& cfg = {});

// boleap: its GP is fitted on the initial design and then at the end of every leap of
// `episodes_per_leap` episodes that leaves budget for another (n = n0, n0 + E, n0 + 2E, ... < budget),
// each fit at the same per-evaluation costs as bo's; a fit takes more likelihood evaluations as n
// grows: kBoLeapEvaluationsBase + kBoLeapEvaluationsPerPoint n (fitted to the runs' diagnostics:
// 172-196 evaluations over the 2 fits of 200-episode runs (n 11-20, 110-120), 1,277-1,876 over the
// 11 fits of 1,000-episode runs on cartpole1 and rastrigin-10). The schedule counts leaps of
// exactly episodes_per_leap; a leap that CMA-ES's stop tests end early adds one (the boleap runs above
// made 11 fits where it counts 10), which the fitted constants absorb.
inline constexpr double kBoLeapEvaluationsBase = 70.0;
inline constexpr double kBoLeapEvaluationsPerPoint = 0.17;
double boleap_own_seconds(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg = {});
// the fits of that schedule over a run
int boleap_fits(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg = {});

}  // namespace dsb
