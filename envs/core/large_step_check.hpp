#pragma once
// Whether an analytic gradient's direction holds over a large step: the loss's slope along the
// unit gradient u = g / |g|, measured by a central difference of Env::loss() over the window
// t in [-H, H] (x + t u, H in normalized units, e.g. 0.05 = 2.5% of the box's width), compared
// with the slope the gradient promises along u, which is |g| > 0.
//  - difference = (f(x + hi u) - f(x + lo u)) / (hi - lo), the window [lo, hi] = [-H, H] shifted
//    along u to stay inside the box [-1, 1]^d, keeping its width 2H where the box allows it (the
//    same rule as the coordinate differences of gradient_check.hpp);
//  - ratio = difference / |g|: 1 when the gradient predicts the loss over the step, near 0 on a
//    plateau at that scale, negative when the loss falls along +g: the gradient points the wrong
//    way, what Antonova et al. report for swing and flip ("gradients point in incorrect, often
//    opposite, directions");
//  - opposed = difference < 0 with a nonzero finite gradient.
// A zero or non-finite gradient has no direction: directed is false, the other fields NaN/false.
// Two loss() calls, on the caller's workspace.
#include <span>

#include "envs/core/env.hpp"

namespace dsb {

struct LargeStepCheck {
  bool directed = false;      // the gradient is nonzero and finite, and the difference finite
  double lo = 0.0, hi = 0.0;  // the window in t, the distance along u
  double difference = 0.0;    // the central difference along u over the window (NaN: none)
  double ratio = 0.0;         // difference / |g| (NaN when not directed)
  bool opposed = false;       // directed and difference < 0
  bool flat = false;          // directed and difference == 0 (the loss the same at both ends)
};

// step H in (0, 0.5]; grad of size env.dim() at x (inside the box). Throws std::invalid_argument
// for a step outside (0, 0.5] or sizes that do not match.
LargeStepCheck check_large_step(const Env& env, Workspace& ws, std::span<const double> x, std::span<const double> grad,
                                double step);

}  // namespace dsb
