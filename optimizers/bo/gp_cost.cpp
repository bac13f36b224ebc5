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

double bo_own_seconds(int dim, std::int64_t budget, const BoConfig& cfg) {
  double n3 = 0.0, n2 = 0.0;
  for_each_fit(dim, budget, cfg, [&](double n) {
    n3 += n * n * n;
    n2 += n * n;
  });
  return kBoEvaluationsPerFit * (kBoSecondsPerN3 * n3 + kBoSecondsPerN2D * n2 * dim);
}

double boleap_own_seconds(int dim, std::int64_t budget) {
  const double d = std::clamp(static_cast<double>(dim), 10.0, 400.0);
  const double per_1000 = 12.6 + (200.0 - 12.6) * (d - 10.0) / 390.0;
  const double scale = static_cast<double>(budget) / 1000.0;
  return per_1000 * scale * scale;
}

}  // namespace dsb
