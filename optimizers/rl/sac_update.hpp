#pragma once
// The math of one SAC gradient step (SB3 sac.py SAC.train), as free functions on plain numbers and
// on Mlp networks, so that tests can compare each piece with hand values and central differences.
// optimizers/rl/sac.hpp strings them together.
//
// Networks (SB3 SAC policies with share_features_extractor = False, flatten features):
//   - actor: one Mlp {obs_dim, h..., 2 action_dim}: rows 0 .. d-1 of its output are the mean,
//     rows d .. 2d-1 the (unclamped) log-std; SB3's separate mu and log_std Linear heads on the
//     last hidden layer are exactly this one output layer split in two;
//   - critic k: Mlp {obs_dim + action_dim, h..., 1} on the input [obs; action] (SB3 concatenates
//     features and actions in this order).
// Batches are matrices with one column per sample, as in optimizers/rl/mlp.hpp.
#include <span>
#include <vector>

#include <Eigen/Dense>

#include "optimizers/rl/gaussian.hpp"
#include "optimizers/rl/mlp.hpp"

namespace dsb {

// Critic target of one transition: y = r + (1 - done) gamma (min_k Q'_k(s', a') - alpha log pi(a'|s')).
double sac_critic_target(double reward, double done, double gamma, double min_q_next, double alpha,
                         double log_prob_next);

// Entropy-coefficient loss -mean_j(log_alpha (log pi_j + target_entropy)) (log pi detached) and
// its derivative with respect to log_alpha, -mean_j(log pi_j + target_entropy). Means run over j
// in increasing order.
double sac_alpha_loss(double log_alpha, std::span<const double> log_prob, double target_entropy);
double sac_alpha_loss_grad(std::span<const double> log_prob, double target_entropy);

// One reparameterised actor pass on a batch: out = actor(obs), per column j a squashed Gaussian
// draw at the given noise eps.col(j) (action_dim x batch).
struct SacActorPass {
  MlpCache cache;                       // of actor.forward(obs)
  std::vector<SquashedGaussian> draws;  // one per sample
  Eigen::MatrixXd actions;              // action_dim x batch, tanh-squashed
  std::vector<double> log_prob;         // batch
};
SacActorPass sac_actor_pass(const Mlp& actor, const Eigen::MatrixXd& obs, const Eigen::MatrixXd& eps);

// [obs; action] stacked: (obs_dim + action_dim) x batch
Eigen::MatrixXd sac_critic_input(const Eigen::MatrixXd& obs, const Eigen::MatrixXd& action);

// min_k Q_k(obs, action) per sample (no caches; the target critics)
std::vector<double> sac_min_q(const std::vector<Mlp>& critics, const Eigen::MatrixXd& obs,
                              const Eigen::MatrixXd& action);

// Critic loss 0.5 sum_k mean_j (Q_k(s_j, a_j) - y_j)^2 (SB3: 0.5 * sum of F.mse_loss). When grads
// is given (one vector of param_count() per critic), ADDS dLoss/dparams of critic k to (*grads)[k].
double sac_critic_loss(const std::vector<Mlp>& critics, const Eigen::MatrixXd& obs, const Eigen::MatrixXd& action,
                       std::span<const double> y, std::vector<std::vector<double>>* grads = nullptr);

// Actor loss mean_j (alpha log pi_j - min_k Q_k(s_j, a_j)) for the actions and log pi of `pass`
// (made by sac_actor_pass on the same obs). When grad is non-empty, ADDS dLoss/d(actor params)
// through the squashed Gaussian (reparameterised, at the pass's noise) and the critics' input
// gradient dQ/da (the critics' parameters are not touched; the minimum's gradient goes to the
// critic that attains it, the first one on a tie, as torch.min).
double sac_actor_loss(const Mlp& actor, const SacActorPass& pass, const std::vector<Mlp>& critics,
                      const Eigen::MatrixXd& obs, double alpha, std::span<double> grad = {});

}  // namespace dsb
