#include "optimizers/bo/gp_cost.hpp"

#include <algorithm>
#include <cmath>

namespace dsb {

namespace {

// fn(n) for the points n at which BoSurrogate::add refits: the initial design's one fit, then
// every point up to refit_every_until, then at every refit_growth of growth
template <class Fn>
void for_each_fit(int dim, std::int64_t budget, const BoConfig& cfg, Fn&& fn) {
  const std::int64_t first = std::min<std::int64_t>(cfg.initial_points_for(dim), budget);
  std::int64_t last_fit = 0;
  for (std::int64_t n = first; n <= budget; ++n) {
    const bool fit = n == first || n <= cfg.refit_every_until ||
        n >= static_cast<std::int64_t>(std::ceil((1.0 + cfg.refit_growth) * static_cast<double>(last_fit)));
    if (!fit) continue;
    fn(static_cast<double>(n));
    last_fit = n;
  }
}

}  // namespace

int bo_fits(int dim, std::int64_t budget, const BoConfig& cfg) {
  int fits = 0;
  for_each_fit(dim, budget, cfg, [&](double) { ++fits; });
  return fits;
}

int lcb_evaluations(const LcbConfig& cfg) { return cfg.raw_samples + cfg.restarts * cfg.max_evaluations; }

double bo_acquisition_seconds(int dim, std::int64_t budget, const BoConfig& cfg) {
  // one LCB minimization per episode after the initial design, with the n points simulated so far
  double terms = 0.0;
  for (std::int64_t n = std::min<std::int64_t>(cfg.initial_points_for(dim), budget); n < budget; ++n) {
    const double nd = static_cast<double>(n);
    terms += nd * (nd + dim);
  }
  return kBoSecondsPerLcbTerm * lcb_evaluations(cfg.lcb) * terms;
}

double bo_own_seconds(int dim, std::int64_t budget, const BoConfig& cfg) {
  double n3 = 0.0, n2 = 0.0;
  for_each_fit(dim, budget, cfg, [&](double n) {
    n3 += n * n * n;
    n2 += n * n;
  });
  return kBoEvaluationsPerFit * (kBoSecondsPerN3 * n3 + kBoSecondsPerN2D * n2 * dim) +
      bo_acquisition_seconds(dim, budget, cfg);
}

namespace {

// fn(n) for the points n at which BoLeap refits: the initial design, then after every leap that
// leaves budget for another
template <class Fn>
void for_each_leap_fit(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg, Fn&& fn) {
  const std::int64_t first = std::min<std::int64_t>(cfg.initial_points_for(dim), budget);
  for (std::int64_t n = first; n == first || n < budget; n += std::max(1, episodes_per_leap))
    fn(static_cast<double>(n));
}

}  // namespace

int boleap_fits(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg) {
  int fits = 0;
  for_each_leap_fit(dim, budget, episodes_per_leap, cfg, [&](double) { ++fits; });
  return fits;
}

double boleap_own_seconds(int dim, std::int64_t budget, int episodes_per_leap, const BoConfig& cfg) {
  double seconds = 0.0;
  for_each_leap_fit(dim, budget, episodes_per_leap, cfg, [&](double n) {
    const double evaluations = kBoLeapEvaluationsBase + kBoLeapEvaluationsPerPoint * n;
    seconds += evaluations * (kBoSecondsPerN3 * n * n * n + kBoSecondsPerN2D * n * n * dim);
  });
  return seconds;
}

}  // namespace dsb
