#pragma once
// What the budget wrapper refuses before it simulates: an optimizer's malformed request is a bug
// in the optimizer (std::logic_error naming the bad value), never an episode.
#include <cstddef>
#include <span>

#include "envs/core/env.hpp"

namespace dsb {

// x of the env's dimension, every coordinate in [-1, 1]
void check_point(const Env& env, std::span<const double> x);
// a gradient buffer of the env's dimension
void check_gradient_buffer(const Env& env, std::span<const double> grad);
// a batch of `points` points of dimension d in `values` values
void check_batch(std::size_t values, std::size_t points, std::size_t d);
// an RL action of the view's size, every value in [-1, 1]
void check_action(const Env& env, int action_dim, std::span<const double> action);

}  // namespace dsb
