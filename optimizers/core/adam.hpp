#pragma once
// Adam (Kingma & Ba 2015) on the normalized box, each iterate clipped to [-1, 1]. Shared by gd,
// rand-descents and boleap's local descents.
#include <cmath>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "common/det_math.hpp"

namespace dsb {

struct AdamConfig {
  double lr = 0.1;
  double beta1 = 0.9;
  double beta2 = 0.999;
  double eps = 1e-8;
  void validate(const std::string& owner) const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(lr, beta1, beta2, eps)
};

class Adam {
 public:
  Adam(const AdamConfig& cfg, int dim) : cfg_(cfg), m_(dim, 0.0), v_(dim, 0.0) {}
  void reset() {
    std::fill(m_.begin(), m_.end(), 0.0);
    std::fill(v_.begin(), v_.end(), 0.0);
    t_ = 0;
  }
  // x <- clip(x - lr * mhat / (sqrt(vhat) + eps), -1, 1)   (Adam update, eq. in Alg. 1 of the paper)
  void step(std::span<double> x, std::span<const double> grad) { update(x, grad, true); }
  // the same without the box (network parameters: optimizers/rl/network_adam.hpp)
  void step_unbounded(std::span<double> x, std::span<const double> grad) { update(x, grad, false); }
  int steps() const { return t_; }
  const AdamConfig& config() const { return cfg_; }
  void set_lr(double lr) { cfg_.lr = lr; }

 private:
  // m <- b1 m + (1 - b1) g; v <- b2 v + (1 - b2) g^2; x <- x - lr mhat / (sqrt(vhat) + eps)
  void update(std::span<double> x, std::span<const double> grad, bool clip_to_box) {
    ++t_;
    const double c1 = 1.0 - dm::pow(cfg_.beta1, t_);
    const double c2 = 1.0 - dm::pow(cfg_.beta2, t_);
    for (std::size_t i = 0; i < x.size(); ++i) {
      m_[i] = cfg_.beta1 * m_[i] + (1.0 - cfg_.beta1) * grad[i];
      v_[i] = cfg_.beta2 * v_[i] + (1.0 - cfg_.beta2) * grad[i] * grad[i];
      const double mhat = m_[i] / c1;
      const double vhat = v_[i] / c2;
      const double xi = x[i] - cfg_.lr * mhat / (std::sqrt(vhat) + cfg_.eps);
      x[i] = !clip_to_box ? xi : (xi < -1.0 ? -1.0 : (xi > 1.0 ? 1.0 : xi));
    }
  }

  AdamConfig cfg_;
  std::vector<double> m_, v_;
  int t_ = 0;
};

}  // namespace dsb
