#pragma once
// One gradient checker, used by `harness gradcheck` and by every gradient test (in the style of
// Ceres' GradientChecker): an env's analytic gradient against finite differences of its loss at
// a point, with per-coordinate errors, the worst error and its coordinate, and a verdict; and
// gradient-quality statistics over seeded random points (how often the gradient agrees with
// central differences, how often it is exactly zero, the distribution of its norm, and how often
// its direction is contradicted by a large-step difference along it: envs/core/large_step_check.hpp).
//
// The guard that the finite differences are not the analytic code path:
//  - finite differences are taken only through Env::loss() (the value-only path),
//  - the analytic gradient only through Env::loss_and_grad(),
//  - at x both are called and must return the same loss: bit for bit by default
//    (GradientCheckOptions::value_tolerance = 0), because the project promises the same bits for
//    the same computation, and the runner records the loss of whichever path an optimizer asked
//    for, so a gradient method and a gradient-free one at the same x must record the same number.
//    Two NaNs (the same blow-up on both paths) agree.
// What the guard catches: a loss_and_grad() whose forward pass has drifted from loss() (a second
// copy of the simulation, a tape recorded with other constants, another reduction order), so that
// the gradient checked belongs to a function other than the one the optimizers are scored on.
// Also flagged, never a failure: an analytic gradient bit-equal to the checker's own central
// differences in every nonzero coordinate (what a "gradient" computed by the same finite
// differences gives; a function linear along those coordinates gives it too).
// What it does not catch: a loss() that is loss_and_grad() with the gradient thrown away (the
// values then agree trivially; the survey's time per call of each path is a hint, a ratio near 1
// says loss() may do the gradient's work, but never a verdict); a gradient computed by finite
// differences with another step (it looks like a slightly inaccurate analytic gradient); a bug
// shared by both paths (the checker sees a consistent function and its consistent derivative).
#include <cstdint>
#include <span>
#include <vector>

#include "envs/core/env.hpp"
#include "envs/core/large_step_check.hpp"

namespace dsb {

// cos 25 degrees: the gradient "points the way the differences do" above it
inline constexpr double kAlignedCosine = 0.90630778703665;

struct GradientCheckOptions {
  // h, normalized units: the window is [x - h, x + h], shifted to [1 - 2h, 1] or [-1, -1 + 2h]
  // (a one-sided difference over the same width) where it would leave the box
  double step = 1e-6;
  // a coordinate agrees when its relative error (see CoordinateCheck) is <= tolerance
  double tolerance = 1e-4;
  // the relative error's denominator floor: relative_floor * max_j |central_j| + absolute_floor
  double relative_floor = 1e-3;
  double absolute_floor = 0.0;
  // loss() and loss_and_grad() agree at x when |a - b| <= value_tolerance * |a|; 0 = bit-equal
  double value_tolerance = 0.0;
  // throws ConfigError naming the field: step outside (0, 0.1), tolerance not > 0, a floor or
  // value_tolerance negative, any non-finite value
  void validate() const;
};

// Finite differences of Env::loss() along one coordinate over the window above.
struct Differences {
  double central;  // (f(hi) - f(lo)) / (hi - lo)
  double right;    // (f(hi) - f(x)) / (hi - x); NaN when the window has no room right of x
  double left;     // (f(x) - f(lo)) / (x - lo); NaN when it has none left of x
};
// loss_at_x is env.loss(x); the overload without it computes it (one more rollout)
Differences finite_differences(const Env& env, std::span<const double> x, int i, double step, double loss_at_x);
Differences finite_differences(const Env& env, std::span<const double> x, int i, double step);

struct CoordinateCheck {
  double analytic = 0.0;  // dLoss/dx_i from loss_and_grad()
  Differences differences{};
  double absolute_error = 0.0;  // |analytic - central|
  // absolute_error / (|central| + relative_floor * max_j |central_j| + absolute_floor); 0 when
  // absolute_error is 0, +inf when only the denominator is, NaN when anything is NaN
  double relative_error = 0.0;
  bool agrees = false;  // relative_error <= tolerance
};

struct GradientCheckResult {
  double loss = 0.0;             // from loss_and_grad()
  double value_path_loss = 0.0;  // from loss()
  bool value_agrees = false;
  std::vector<CoordinateCheck> coordinates;
  double gradient_norm = 0.0;    // Euclidean norm of the analytic gradient
  double max_abs_central = 0.0;  // max_j |central_j|
  double worst_absolute_error = 0.0;
  double worst_relative_error = 0.0;      // NaN when any coordinate's is
  int worst_coordinate = -1;              // where worst_relative_error is; -1 for dim 0
  bool finite = false;                    // both losses, every gradient component, every central difference
  bool exactly_zero = false;              // every analytic component is 0 (and finite)
  bool bit_equal_to_differences = false;  // see the header comment; not a failure
  bool gradient_agrees = false;           // every coordinate agrees
  // cos of the angle between the analytic gradient and the central differences over the checked
  // coordinates: where a loss has many small jumps the two can disagree coordinate by coordinate
  // and still point the same way (or not); NaN when either vector is zero or not finite
  double direction_cosine = 0.0;
  bool passed = false;                 // finite, value_agrees and gradient_agrees
  double seconds_loss_and_grad = 0.0;  // wall time of the loss_and_grad() call
  double seconds_per_loss = 0.0;       // mean wall time of the loss() calls
};

// Checks env's gradient at x (size dim, inside [-1, 1]): one loss_and_grad() and 2 dim + 1
// loss() calls. Throws std::invalid_argument for a non-differentiable env or x of the wrong size
// or outside the box, and ConfigError for invalid options.
GradientCheckResult check_gradient(const Env& env, std::span<const double> x, const GradientCheckOptions& options = {});
// The same check along the given coordinates only (2 size + 1 loss() calls; `coordinates` of the
// result follow their order, worst_coordinate names the env's coordinate, max_abs_central and the
// relative errors' floor are over these coordinates, gradient_norm is the whole gradient's), with
// every rollout on `ws` (a 2-D landscape checks its two directions at each grid point this way).
GradientCheckResult check_gradient_along(const Env& env, Workspace& ws, std::span<const double> x,
                                         std::span<const int> coordinates, const GradientCheckOptions& options);

struct GradientSurveyOptions {
  GradientCheckOptions check;
  int points = 3;          // random points
  std::uint64_t seed = 0;  // of our own Rng (common/rng.hpp)
  double amplitude = 0.5;  // points uniform in [-amplitude, amplitude]^dim
  // H of the large-step check along the gradient at each point (normalized units; 2 more loss()
  // calls per point); 0 = no large-step check
  double large_step = 0.05;
  // throws ConfigError naming the field (check's fields too): points < 1, amplitude outside (0, 1],
  // large_step outside [0, 0.5]
  void validate() const;
};

// min, quartiles and max by linear interpolation between order statistics (position
// p (n - 1) in the sorted values, numpy's default); all NaN for no values
struct Quartiles {
  double min, q1, median, q3, max;
};
Quartiles quartiles(std::vector<double> values);

struct GradientSurvey {
  std::vector<std::vector<double>> x;  // the points, in drawing order
  std::vector<GradientCheckResult> checks;
  int points = 0;
  int agreeing = 0;                   // gradient_agrees
  int aligned = 0;                    // direction_cosine > kAlignedCosine (within 25 degrees)
  int opposed = 0;                    // direction_cosine < 0
  int directed = 0;                   // points with a direction_cosine (not NaN)
  int exactly_zero = 0;               // exactly_zero
  int non_finite = 0;                 // !finite
  int value_mismatches = 0;           // !value_agrees
  int bit_equal_to_differences = 0;   // bit_equal_to_differences
  Quartiles gradient_norm{};          // over the points with a finite gradient
  double worst_relative_error = 0.0;  // NaN when any point's is
  int worst_point = -1, worst_coordinate = -1;
  double seconds_per_loss_and_grad = 0.0;  // mean over the points
  double seconds_per_loss = 0.0;
  bool passed = false;  // every point passed (the large-step check never fails a point)
  // the large-step check at each point (empty when options.large_step is 0), and its counts
  std::vector<LargeStepCheck> large_steps;
  int large_step_directed = 0;   // points with a direction (nonzero finite gradient, finite difference)
  int large_step_opposed = 0;    // of those, the loss falls along +g over the window
  int large_step_flat = 0;       // of those, the loss is the same at both ends of the window
  Quartiles large_step_ratio{};  // difference / |g| over the directed points
};

// The points: x_i = amplitude * rng.uniform(-1, 1), coordinate by coordinate, point by point,
// from Rng(seed); then check_gradient at each, and check_large_step with the gradient it got.
GradientSurvey survey_gradient(const Env& env, const GradientSurveyOptions& options);

}  // namespace dsb
