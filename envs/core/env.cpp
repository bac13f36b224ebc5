#include "envs/core/env.hpp"

#include <stdexcept>

namespace dsb {

double Env::loss_and_grad(std::span<const double>, std::span<double>) const {
  throw std::logic_error("env '" + name() + "' is not differentiable");
}

}  // namespace dsb
