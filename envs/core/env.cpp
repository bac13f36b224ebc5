#include "envs/core/env.hpp"

#include <limits>
#include <stdexcept>

#include "common/parallel.hpp"

namespace dsb {

double Env::rollout_with_grad(std::span<const double>, std::span<double>, Workspace&, ThreadTeam&) const {
  throw std::logic_error("env '" + name() + "' is not differentiable");
}

double Env::episode_metric(const Workspace&) const { return std::numeric_limits<double>::quiet_NaN(); }

double Env::loss(std::span<const double> x) const {
  const auto ws = make_workspace();
  return rollout(x, *ws, serial_team());
}

double Env::loss_and_grad(std::span<const double> x, std::span<double> grad) const {
  const auto ws = make_workspace();
  return rollout_with_grad(x, grad, *ws, serial_team());
}

}  // namespace dsb
