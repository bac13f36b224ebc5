#include "optimizers/rl/network_adam.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/det_math.hpp"

namespace dsb {

NetworkAdam::NetworkAdam(const AdamConfig& cfg, std::size_t dim) : cfg_(cfg), m_(dim, 0.0), v_(dim, 0.0) {
  cfg_.validate("network_adam");
}

void NetworkAdam::reset() {
  std::fill(m_.begin(), m_.end(), 0.0);
  std::fill(v_.begin(), v_.end(), 0.0);
  t_ = 0;
}

void NetworkAdam::step(std::span<double> p, std::span<const double> g) {
  if (p.size() != m_.size() || g.size() != m_.size())
    throw std::invalid_argument("NetworkAdam::step: parameters and gradient must have the dimension "
                                "given at construction");
  ++t_;
  // bias corrections 1 - b1^t, 1 - b2^t
  const double c1 = 1.0 - dm::pow(cfg_.beta1, t_);
  const double c2 = 1.0 - dm::pow(cfg_.beta2, t_);
  for (std::size_t i = 0; i < p.size(); ++i) {
    // moments (Alg. 1 lines 7-8), bias-corrected (lines 9-10), update (line 11)
    m_[i] = cfg_.beta1 * m_[i] + (1.0 - cfg_.beta1) * g[i];
    v_[i] = cfg_.beta2 * v_[i] + (1.0 - cfg_.beta2) * g[i] * g[i];
    const double mhat = m_[i] / c1;
    const double vhat = v_[i] / c2;
    p[i] -= cfg_.lr * mhat / (std::sqrt(vhat) + cfg_.eps);
  }
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
