#include "harness/run/call_checks.hpp"

#include <stdexcept>
#include <string>

#include "common/number_text.hpp"
#include "common/unit_box.hpp"

namespace dsb {

void check_point(const Env& env, std::span<const double> x) {
  if (static_cast<int>(x.size()) != env.dim())
    throw std::logic_error("optimizer asked for a point of dimension " + std::to_string(x.size()) + " on env '" +
                           env.name() + "' of dimension " + std::to_string(env.dim()));
  if (const auto i = first_outside_box(x); i >= 0)
    throw std::logic_error("optimizer asked for x[" + std::to_string(i) + "] = " + number_text(x[i]) +
                           " outside [-1, 1]");
}

void check_gradient_buffer(const Env& env, std::span<const double> grad) {
  if (static_cast<int>(grad.size()) != env.dim()) throw std::logic_error("gradient buffer has the wrong size");
}

void check_batch(std::size_t values, std::size_t points, std::size_t d) {
  if (values != points * d)
    throw std::logic_error("batch of " + std::to_string(points) + " points has " + std::to_string(values) +
                           " values, expected " + std::to_string(points * d));
}

void check_action(const Env& env, int action_dim, std::span<const double> action) {
  if (static_cast<int>(action.size()) != action_dim)
    throw std::logic_error("optimizer gave an action of size " + std::to_string(action.size()) + " on env '" +
                           env.name() + "' with " + std::to_string(action_dim) + " actions");
  for (std::size_t i = 0; i < action.size(); ++i)
    if (!(action[i] >= -1.0 && action[i] <= 1.0))
      throw std::logic_error("optimizer gave action[" + std::to_string(i) + "] = " + std::to_string(action[i]) +
                             " outside [-1, 1]");
}

}  // namespace dsb
