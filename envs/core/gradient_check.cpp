#include "envs/core/gradient_check.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/error.hpp"
#include "common/number_text.hpp"
#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "common/unit_box.hpp"

namespace dsb {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void require_finite_nonnegative(const char* field, double v) {
  if (!std::isfinite(v) || v < 0.0)
    throw ConfigError("gradcheck", field, "must be a finite number >= 0, got " + number_text(v));
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void require_in_box(const Env& env, std::span<const double> x) {
  if (static_cast<int>(x.size()) != env.dim())
    throw std::invalid_argument("gradient check of '" + env.name() + "': x has size " + std::to_string(x.size()) +
                                ", expected " + std::to_string(env.dim()));
  if (const auto i = first_outside_box(x); i >= 0)
    throw std::invalid_argument("gradient check of '" + env.name() + "': x[" + std::to_string(i) +
                                "] = " + number_text(x[i]) + " is outside [-1, 1]");
}

// both NaN (the same blow-up), or within value_tolerance relative (0: bit-equal)
bool values_agree(double a, double b, double value_tolerance) {
  if (std::isnan(a) && std::isnan(b)) return true;
  if (a == b) return true;
  return std::abs(a - b) <= value_tolerance * std::abs(a);
}

}  // namespace

void GradientCheckOptions::validate() const {
  if (!(std::isfinite(step) && step > 0.0 && step < 0.1))
    throw ConfigError("gradcheck", "step", "must be in (0, 0.1), got " + number_text(step));
  if (!(std::isfinite(tolerance) && tolerance > 0.0))
    throw ConfigError("gradcheck", "tolerance", "must be a finite number > 0, got " + number_text(tolerance));
  require_finite_nonnegative("relative_floor", relative_floor);
  require_finite_nonnegative("absolute_floor", absolute_floor);
  require_finite_nonnegative("value_tolerance", value_tolerance);
}

void GradientSurveyOptions::validate() const {
  check.validate();
  if (points < 1) throw ConfigError("gradcheck", "points", "must be >= 1, got " + std::to_string(points));
  if (!(std::isfinite(amplitude) && amplitude > 0.0 && amplitude <= 1.0))
    throw ConfigError("gradcheck", "amplitude", "must be in (0, 1], got " + number_text(amplitude));
  if (!(std::isfinite(large_step) && large_step >= 0.0 && large_step <= 0.5))
    throw ConfigError("gradcheck", "large_step", "must be in [0, 0.5] (0 = off), got " + number_text(large_step));
}

namespace {

// the differences along coordinate i, every rollout on one workspace
Differences differences_on(const Env& env, Workspace& ws, std::span<const double> x_in, int i, double step,
                           double loss_at_x) {
  require_in_box(env, x_in);
  if (i < 0 || i >= env.dim())
    throw std::invalid_argument("gradient check of '" + env.name() + "': coordinate " + std::to_string(i) +
                                " outside 0.." + std::to_string(env.dim() - 1));
  std::vector<double> x(x_in.begin(), x_in.end());
  const double xi = x[i];
  // the window [x - h, x + h], shifted inside [-1, 1] keeping its width 2h
  double lo = xi - step, hi = xi + step;
  if (hi > 1.0) {
    hi = 1.0;
    lo = 1.0 - 2.0 * step;
  } else if (lo < -1.0) {
    lo = -1.0;
    hi = -1.0 + 2.0 * step;
  }
  x[i] = hi;
  const double fp = env.loss(x, ws, serial_team());
  x[i] = lo;
  const double fm = env.loss(x, ws, serial_team());
  // central (or one-sided) difference over the window, and the two one-sided ones from x
  Differences d;
  d.central = (fp - fm) / (hi - lo);
  d.right = hi > xi ? (fp - loss_at_x) / (hi - xi) : kNaN;
  d.left = xi > lo ? (loss_at_x - fm) / (xi - lo) : kNaN;
  return d;
}

}  // namespace

Differences finite_differences(const Env& env, std::span<const double> x, int i, double step, double loss_at_x) {
  const auto ws = env.make_workspace();
  return differences_on(env, *ws, x, i, step, loss_at_x);
}

Differences finite_differences(const Env& env, std::span<const double> x, int i, double step) {
  require_in_box(env, x);
  const auto ws = env.make_workspace();
  return differences_on(env, *ws, x, i, step, env.loss(x, *ws, serial_team()));
}

GradientCheckResult check_gradient(const Env& env, std::span<const double> x, const GradientCheckOptions& options) {
  // every rollout of the check reuses one workspace
  const auto ws = env.make_workspace();
  std::vector<int> all(std::max(env.dim(), 0));
  for (int i = 0; i < env.dim(); ++i) all[i] = i;
  return check_gradient_along(env, *ws, x, all, options);
}

GradientCheckResult check_gradient_along(const Env& env, Workspace& ws, std::span<const double> x,
                                         std::span<const int> coordinates, const GradientCheckOptions& options) {
  options.validate();
  if (!env.differentiable())
    throw std::invalid_argument("gradient check: env '" + env.name() + "' is not differentiable");
  require_in_box(env, x);
  const int n = static_cast<int>(coordinates.size());
  GradientCheckResult r;

  // the analytic path, once
  std::vector<double> grad(env.dim());
  auto start = std::chrono::steady_clock::now();
  r.loss = env.loss_and_grad(x, grad, ws, serial_team());
  r.seconds_loss_and_grad = seconds_since(start);

  // the value-only path: the loss at x and the differences
  start = std::chrono::steady_clock::now();
  r.value_path_loss = env.loss(x, ws, serial_team());
  r.coordinates.resize(n);
  for (int k = 0; k < n; ++k) {
    r.coordinates[k].analytic = grad[coordinates[k]];
    r.coordinates[k].differences = differences_on(env, ws, x, coordinates[k], options.step, r.value_path_loss);
  }
  r.seconds_per_loss = seconds_since(start) / (2 * n + 1);
  r.value_agrees = values_agree(r.value_path_loss, r.loss, options.value_tolerance);

  r.finite = std::isfinite(r.loss) && std::isfinite(r.value_path_loss);
  double norm2 = 0.0;
  for (const double g : grad) {
    r.finite = r.finite && std::isfinite(g);
    norm2 += g * g;
  }
  bool zero = true, bit_equal = true, any_nonzero = false;
  for (const auto& c : r.coordinates) {
    r.finite = r.finite && std::isfinite(c.differences.central);
    r.max_abs_central = std::max(r.max_abs_central, std::abs(c.differences.central));
    zero = zero && c.analytic == 0.0;
    if (c.analytic != 0.0) {
      any_nonzero = true;
      bit_equal = bit_equal && c.analytic == c.differences.central;
    }
  }
  r.gradient_norm = std::sqrt(norm2);
  r.exactly_zero = zero;
  r.bit_equal_to_differences = any_nonzero && bit_equal;

  // relative error: |g_i - c_i| / (|c_i| + relative_floor max_j |c_j| + absolute_floor)
  const double floor = options.relative_floor * r.max_abs_central + options.absolute_floor;
  r.gradient_agrees = true;
  for (int k = 0; k < n; ++k) {
    auto& c = r.coordinates[k];
    c.absolute_error = std::abs(c.analytic - c.differences.central);
    const double denominator = std::abs(c.differences.central) + floor;
    c.relative_error = c.absolute_error == 0.0 ? 0.0 : c.absolute_error / denominator;
    c.agrees = c.relative_error <= options.tolerance;  // false for NaN
    r.gradient_agrees = r.gradient_agrees && c.agrees;
    if (!(c.absolute_error <= r.worst_absolute_error)) r.worst_absolute_error = c.absolute_error;
    // NaN counts as the worst
    if (r.worst_coordinate < 0 ||
        (!std::isnan(r.worst_relative_error) && !(c.relative_error <= r.worst_relative_error))) {
      r.worst_relative_error = c.relative_error;
      r.worst_coordinate = coordinates[k];
    }
  }
  double dot = 0.0, analytic2 = 0.0, central2 = 0.0;
  for (const auto& c : r.coordinates) {
    dot += c.analytic * c.differences.central;
    analytic2 += c.analytic * c.analytic;
    central2 += c.differences.central * c.differences.central;
  }
  const double norms = std::sqrt(analytic2) * std::sqrt(central2);
  r.direction_cosine = std::isfinite(dot) && std::isfinite(norms) && norms > 0.0 ? dot / norms : kNaN;
  r.passed = r.finite && r.value_agrees && r.gradient_agrees;
  return r;
}

Quartiles quartiles(std::vector<double> values) {
  if (values.empty()) return {kNaN, kNaN, kNaN, kNaN, kNaN};
  std::sort(values.begin(), values.end());
  // linear interpolation at position p (n - 1) between order statistics
  auto at = [&](double p) {
    const double pos = p * static_cast<double>(values.size() - 1);
    const auto k = static_cast<std::size_t>(pos);
    if (k + 1 >= values.size()) return values.back();
    return values[k] + (pos - static_cast<double>(k)) * (values[k + 1] - values[k]);
  };
  return {values.front(), at(0.25), at(0.5), at(0.75), values.back()};
}

GradientSurvey survey_gradient(const Env& env, const GradientSurveyOptions& options) {
  options.validate();
  const int n = env.dim();
  GradientSurvey s;
  s.points = options.points;
  Rng rng(options.seed);
  std::vector<double> norms, ratios;
  const auto ws = env.make_workspace();  // the large-step check's rollouts
  std::vector<double> grad(n);
  for (int p = 0; p < options.points; ++p) {
    std::vector<double> x(n);
    for (auto& xi : x) xi = options.amplitude * rng.uniform(-1.0, 1.0);
    auto r = check_gradient(env, x, options.check);
    if (options.large_step > 0.0) {
      for (int i = 0; i < n; ++i) grad[i] = r.coordinates[i].analytic;
      const auto& l = s.large_steps.emplace_back(check_large_step(env, *ws, x, grad, options.large_step));
      if (l.directed) {
        ++s.large_step_directed;
        s.large_step_opposed += l.opposed;
        s.large_step_flat += l.flat;
        ratios.push_back(l.ratio);
      }
    }
    s.agreeing += r.gradient_agrees;
    if (!std::isnan(r.direction_cosine)) {
      ++s.directed;
      s.aligned += r.direction_cosine > kAlignedCosine;
      s.opposed += r.direction_cosine < 0.0;
    }
    s.exactly_zero += r.exactly_zero;
    s.non_finite += !r.finite;
    s.value_mismatches += !r.value_agrees;
    s.bit_equal_to_differences += r.bit_equal_to_differences;
    if (std::isfinite(r.gradient_norm)) norms.push_back(r.gradient_norm);
    s.seconds_per_loss_and_grad += r.seconds_loss_and_grad / options.points;
    s.seconds_per_loss += r.seconds_per_loss / options.points;
    // NaN counts as the worst
    if (s.worst_point < 0 ||
        (!std::isnan(s.worst_relative_error) && !(r.worst_relative_error <= s.worst_relative_error))) {
      s.worst_relative_error = r.worst_relative_error;
      s.worst_point = p;
      s.worst_coordinate = r.worst_coordinate;
    }
    s.x.push_back(std::move(x));
    s.checks.push_back(std::move(r));
  }
  s.gradient_norm = quartiles(std::move(norms));
  s.large_step_ratio = quartiles(std::move(ratios));
  s.passed = std::all_of(s.checks.begin(), s.checks.end(), [](const auto& r) { return r.passed; });
  return s;
}

}  // namespace dsb
