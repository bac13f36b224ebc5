#include "envs/core/large_step_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/parallel.hpp"

namespace dsb {

LargeStepCheck check_large_step(const Env& env, Workspace& ws, std::span<const double> x, std::span<const double> grad,
                                double step) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (!(step > 0.0 && step <= 0.5))
    throw std::invalid_argument("large-step check: step must be in (0, 0.5], got " + std::to_string(step));
  const int n = env.dim();
  if (static_cast<int>(x.size()) != n || static_cast<int>(grad.size()) != n)
    throw std::invalid_argument("large-step check of '" + env.name() + "': x or gradient of the wrong size");
  LargeStepCheck r;
  r.difference = r.ratio = kNaN;
  double norm2 = 0.0;
  for (const double g : grad) norm2 += g * g;
  const double norm = std::sqrt(norm2);
  if (!(std::isfinite(norm) && norm > 0.0)) return r;

  // u = g / |g|; the t for which x + t u stays in [-1, 1]^d is [t_min, t_max] (t_min <= 0 <= t_max)
  std::vector<double> u(n);
  double t_min = -std::numeric_limits<double>::infinity(), t_max = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    u[i] = grad[i] / norm;
    if (u[i] > 0.0) {
      t_max = std::min(t_max, (1.0 - x[i]) / u[i]);
      t_min = std::max(t_min, (-1.0 - x[i]) / u[i]);
    } else if (u[i] < 0.0) {
      t_max = std::min(t_max, (-1.0 - x[i]) / u[i]);
      t_min = std::max(t_min, (1.0 - x[i]) / u[i]);
    }
  }
  // the window [-H, H], shifted inside [t_min, t_max] keeping its width 2H where it fits
  r.lo = -step;
  r.hi = step;
  if (r.hi > t_max) {
    r.hi = t_max;
    r.lo = std::max(t_max - 2.0 * step, t_min);
  } else if (r.lo < t_min) {
    r.lo = t_min;
    r.hi = std::min(t_min + 2.0 * step, t_max);
  }
  if (!(r.hi > r.lo)) return r;  // x on a corner with the gradient pointing out of the box

  std::vector<double> at(n);
  auto loss_at = [&](double t) {
    for (int i = 0; i < n; ++i) at[i] = std::clamp(x[i] + t * u[i], -1.0, 1.0);  // rounding only
    return env.loss(at, ws, serial_team());
  };
  const double f_hi = loss_at(r.hi);
  const double f_lo = loss_at(r.lo);
  r.difference = (f_hi - f_lo) / (r.hi - r.lo);
  if (!std::isfinite(r.difference)) return r;
  r.directed = true;
  r.ratio = r.difference / norm;
  r.opposed = r.difference < 0.0;
  r.flat = r.difference == 0.0;
  return r;
}

}  // namespace dsb
