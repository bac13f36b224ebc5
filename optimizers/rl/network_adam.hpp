#pragma once
// Optimizer pieces for network parameters (the RL baselines): Adam without the box clip of
// optimizers/core/adam.hpp, torch's clip_grad_norm_ and SB3's polyak_update. All act on the one
// flat parameter / gradient span of an Mlp (optimizers/rl/mlp.hpp).
#include <cstddef>
#include <span>
#include <vector>

#include "optimizers/core/adam.hpp"

namespace dsb {

// Adam (Kingma & Ba 2015, Alg. 1) as torch.optim.Adam without weight decay or amsgrad:
//   m <- b1 m + (1 - b1) g;  v <- b2 v + (1 - b2) g^2
//   p <- p - lr * mhat / (sqrt(vhat) + eps),  mhat = m / (1 - b1^t),  vhat = v / (1 - b2^t)
// Config: AdamConfig (lr, beta1, beta2, eps; validated by the owner). SB3 uses lr 3e-4 with
// eps 1e-5 for PPO and torch's default eps 1e-8 for SAC. torch evaluates the same expression as
// p - (lr / (1 - b1^t)) m / (sqrt(v) / sqrt(1 - b2^t) + eps): equal up to rounding.
class NetworkAdam {
 public:
  // throws ConfigError (owner "network_adam") naming the bad field of cfg
  NetworkAdam(const AdamConfig& cfg, std::size_t dim);
  void reset() { adam_.reset(); }
  // one update of p (dim) with gradient g (dim): core Adam's arithmetic without the box clip;
  // throws std::invalid_argument on a size mismatch
  void step(std::span<double> p, std::span<const double> g);
  int steps() const { return adam_.steps(); }
  const AdamConfig& config() const { return adam_.config(); }
  void set_lr(double lr) { adam_.set_lr(lr); }  // for learning-rate schedules

 private:
  std::size_t dim_;
  Adam adam_;
};

// torch.nn.utils.clip_grad_norm_ (one parameter group, 2-norm): n = |g|_2; if
// c = max_norm / (n + 1e-6) < 1, g <- c g. Returns n (before clipping), as torch does.
double clip_grad_norm(std::span<double> g, double max_norm);

// SB3 polyak_update: target <- (1 - tau) target + tau source (elementwise, same sizes)
void polyak_update(std::span<double> target, std::span<const double> source, double tau);

}  // namespace dsb
