#include "optimizers/rl/network_adam.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/det_math.hpp"

namespace dsb {

NetworkAdam::NetworkAdam(const AdamConfig& cfg, std::size_t dim) : dim_(dim), adam_(cfg, static_cast<int>(dim)) {
  cfg.validate("network_adam");
}

void NetworkAdam::step(std::span<double> p, std::span<const double> g) {
  if (p.size() != dim_ || g.size() != dim_)
    throw std::invalid_argument(
        "NetworkAdam::step: parameters and gradient must have the dimension "
        "given at construction");
  adam_.step_unbounded(p, g);
}

double clip_grad_norm(std::span<double> g, double max_norm) {
  // n = sqrt(sum g_i^2), i increasing
  double s = 0.0;
  for (double x : g) s += x * x;
  const double n = std::sqrt(s);
  // c = max_norm / (n + 1e-6), applied when < 1
  const double c = max_norm / (n + 1e-6);
  if (c < 1.0)
    for (double& x : g) x *= c;
  return n;
}

void polyak_update(std::span<double> target, std::span<const double> source, double tau) {
  if (target.size() != source.size())
    throw std::invalid_argument("polyak_update: target and source must have the same size");
  for (std::size_t i = 0; i < target.size(); ++i) target[i] = (1.0 - tau) * target[i] + tau * source[i];
}

}  // namespace dsb
