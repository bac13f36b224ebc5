#include "optimizers/rl/sac_update.hpp"

#include <stdexcept>
#include <string>

namespace dsb {

double sac_critic_target(double reward, double done, double gamma, double min_q_next, double alpha,
                         double log_prob_next) {
  // y = r + (1 - d) gamma (min Q' - alpha log pi')
  return reward + (1.0 - done) * gamma * (min_q_next - alpha * log_prob_next);
}

double sac_alpha_loss_grad(std::span<const double> log_prob, double target_entropy) {
  if (log_prob.empty()) throw std::invalid_argument("sac_alpha_loss_grad: empty batch");
  // -mean(log pi + target_entropy)
  double s = 0.0;
  for (double lp : log_prob) s += lp + target_entropy;
  return -s / static_cast<double>(log_prob.size());
}

double sac_alpha_loss(double log_alpha, std::span<const double> log_prob, double target_entropy) {
  // -mean(log_alpha (log pi + target_entropy)) = log_alpha * d/dlog_alpha
  return log_alpha * sac_alpha_loss_grad(log_prob, target_entropy);
}

SacActorPass sac_actor_pass(const Mlp& actor, const Eigen::MatrixXd& obs, const Eigen::MatrixXd& eps) {
  const int d = actor.out_dim() / 2;
  if (actor.out_dim() != 2 * d || eps.rows() != d || eps.cols() != obs.cols())
    throw std::invalid_argument(
        "sac_actor_pass: the actor must output 2 action_dim values and eps be "
        "action_dim x batch");
  SacActorPass p;
  const Eigen::MatrixXd out = actor.forward(obs, &p.cache);
  const Eigen::Index n = obs.cols();
  p.draws.reserve(n);
  p.actions.resize(d, n);
  p.log_prob.resize(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double* col = out.data() + j * out.rows();
    p.draws.push_back(squashed_gaussian(std::span<const double>(col, d), std::span<const double>(col + d, d),
                                        std::span<const double>(eps.data() + j * d, d)));
    for (int i = 0; i < d; ++i) p.actions(i, j) = p.draws.back().a[i];
    p.log_prob[j] = p.draws.back().log_prob;
  }
  return p;
}

Eigen::MatrixXd sac_critic_input(const Eigen::MatrixXd& obs, const Eigen::MatrixXd& action) {
  if (obs.cols() != action.cols()) throw std::invalid_argument("sac_critic_input: batch sizes differ");
  Eigen::MatrixXd x(obs.rows() + action.rows(), obs.cols());
  x.topRows(obs.rows()) = obs;
  x.bottomRows(action.rows()) = action;
  return x;
}

std::vector<double> sac_min_q(const std::vector<Mlp>& critics, const Eigen::MatrixXd& obs,
                              const Eigen::MatrixXd& action) {
  const Eigen::MatrixXd x = sac_critic_input(obs, action);
  std::vector<double> m(obs.cols());
  for (std::size_t k = 0; k < critics.size(); ++k) {
    const Eigen::MatrixXd q = critics[k].forward(x);
    for (Eigen::Index j = 0; j < x.cols(); ++j)
      if (k == 0 || q(0, j) < m[j]) m[j] = q(0, j);
  }
  return m;
}

double sac_critic_loss(const std::vector<Mlp>& critics, const Eigen::MatrixXd& obs, const Eigen::MatrixXd& action,
                       std::span<const double> y, std::vector<std::vector<double>>* grads) {
  const Eigen::MatrixXd x = sac_critic_input(obs, action);
  const Eigen::Index n = x.cols();
  if (y.size() != std::size_t(n)) throw std::invalid_argument("sac_critic_loss: y must hold one value per sample");
  if (grads && grads->size() != critics.size())
    throw std::invalid_argument("sac_critic_loss: one gradient vector per critic");
  const double inv_n = 1.0 / static_cast<double>(n);
  double loss = 0.0;
  for (std::size_t k = 0; k < critics.size(); ++k) {
    MlpCache cache;
    const Eigen::MatrixXd q = critics[k].forward(x, grads ? &cache : nullptr);
    // 0.5 mean_j (q - y)^2; dLoss/dq_j = (q_j - y_j) / n
    double s = 0.0;
    Eigen::MatrixXd dq(1, n);
    for (Eigen::Index j = 0; j < n; ++j) {
      const double r = q(0, j) - y[j];
      s += r * r;
      dq(0, j) = r * inv_n;
    }
    loss += 0.5 * s * inv_n;
    if (grads) critics[k].backward(cache, dq, (*grads)[k]);
  }
  return loss;
}

double sac_actor_loss(const Mlp& actor, const SacActorPass& pass, const std::vector<Mlp>& critics,
                      const Eigen::MatrixXd& obs, double alpha, std::span<double> grad) {
  const Eigen::Index n = obs.cols();
  const int d = static_cast<int>(pass.actions.rows());
  if (pass.actions.cols() != n) throw std::invalid_argument("sac_actor_loss: the pass is of another batch");
  const Eigen::MatrixXd x = sac_critic_input(obs, pass.actions);
  // every critic on (s, a_pi); keep the caches for dQ/da
  std::vector<MlpCache> caches(critics.size());
  std::vector<Eigen::MatrixXd> qs(critics.size());
  for (std::size_t k = 0; k < critics.size(); ++k) qs[k] = critics[k].forward(x, &caches[k]);
  // argmin per sample, the first critic on a tie
  std::vector<std::size_t> arg(n, 0);
  const double inv_n = 1.0 / static_cast<double>(n);
  double loss = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    for (std::size_t k = 1; k < critics.size(); ++k)
      if (qs[k](0, j) < qs[arg[j]](0, j)) arg[j] = k;
    loss += alpha * pass.log_prob[j] - qs[arg[j]](0, j);
  }
  loss *= inv_n;
  if (grad.empty()) return loss;

  // dLoss/da_j = -(1/n) dQ_{arg j}/da_j: backward through each critic with its share of -1/n
  Eigen::MatrixXd d_a = Eigen::MatrixXd::Zero(d, n);
  for (std::size_t k = 0; k < critics.size(); ++k) {
    Eigen::MatrixXd dq = Eigen::MatrixXd::Zero(1, n);
    bool any = false;
    for (Eigen::Index j = 0; j < n; ++j)
      if (arg[j] == k) dq(0, j) = -inv_n, any = true;
    if (!any) continue;
    Eigen::MatrixXd dx;
    critics[k].backward(caches[k], dq, {}, &dx);
    d_a += dx.bottomRows(d);
  }
  // through the squashed Gaussian (dLoss/dlog pi_j = alpha / n) into the actor's output
  Eigen::MatrixXd d_out(2 * d, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    double* col = d_out.data() + j * 2 * d;
    squashed_gaussian_backward(pass.draws[j], std::span<const double>(d_a.data() + j * d, d), alpha * inv_n,
                               std::span<double>(col, d), std::span<double>(col + d, d));
  }
  actor.backward(pass.cache, d_out, grad);
  return loss;
}

}  // namespace dsb
