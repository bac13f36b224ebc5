#pragma once
// `ppo`: a port of Stable-Baselines3's PPO (SB3 ppo.py) with the seed's
// changes, driving an env's per-step view through the budgeted Objective (Objective::rl_*).
//
// Follows SB3: n_steps 2048 decisions per rollout (episodes run on across rollouts), GAE
// (gamma 0.99, lambda 0.95), 10 epochs of shuffled minibatches of 64, clipped surrogate (0.2), no
// value clipping, advantages normalised per minibatch ((A - mean) / (std + 1e-8), std with
// Bessel's correction as torch's), loss = policy + 0.5 value MSE + 0 x entropy, one Adam (lr
// 3e-4, eps 1e-5) over every parameter, global gradient-norm clip 0.5; diagonal Gaussian policy
// with a state-independent log-std starting at 0, actions sampled unclipped, stored unclipped,
// clipped to [-1, 1] for the env; tanh networks with SB3's orthogonal init (hidden gain sqrt 2,
// policy head 0.01, value head 1, biases 0).
// The seed's changes: policy and value networks of 3 hidden layers of 64 (separate networks, as
// SB3's default structure and as net_arch means since SB3 1.8; SB3 1.6 would have shared the
// three layers between them: the seed does not say which it ran); action repeat by the harness
// (RlSpec::action_repeat: one decision = 1 step on the cartpoles, 5 elsewhere); sparse reward:
// 0 at every decision but the last, minus the episode loss at the last.
// Where it departs: an episode's end is terminal (no bootstrap: the loss is the whole payoff and
// nothing follows the fixed horizon); a failed episode (+inf loss) is rewarded with -2 x the
// largest finite loss seen so far in the run (-2 before any; PpoConfig::failed_loss, the rule in
// rl_core.hpp), so a blow-up is the worst outcome without an infinite reward; the rollout that
// the budget cuts short is not trained on.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/rl/mlp.hpp"
#include "optimizers/rl/rl_core.hpp"

namespace dsb {

struct PpoConfig {
  double learning_rate = 3e-4;
  int n_steps = 2048;   // decisions per rollout
  int batch_size = 64;  // minibatch
  int n_epochs = 10;
  double gamma = 0.99;
  double gae_lambda = 0.95;
  double clip_range = 0.2;
  double ent_coef = 0.0;
  double vf_coef = 0.5;
  double max_grad_norm = 0.5;
  double adam_eps = 1e-5;  // SB3 sets it for on-policy algorithms
  double log_std_init = 0.0;
  std::vector<int> hidden = {64, 64, 64};  // the seed's 3 layers of 64 (policy and value alike)
  // a failed episode stands for -2 x the largest finite loss so far, -2 before any (chosen here)
  FailedEpisodeLoss failed_loss{.factor = 2.0, .floor = 0.0, .before_any = 2.0};
  // throws ConfigError("ppo", field, why)
  void validate() const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp); failed_loss only
  // where it is not the default (to_json)
  DSB_CONFIG_FIELDS(learning_rate, n_steps, batch_size, n_epochs, gamma, gae_lambda, clip_range, ent_coef, vf_coef,
                    max_grad_norm, adam_eps, log_std_init, hidden)
};

// The policy mean network, the value network and the log-std. Flat parameter order for the
// gradient and Adam: [policy params | value params | log_std].
struct PpoNetworks {
  Mlp policy, value;            // obs -> mean (action_dim), obs -> V (1)
  std::vector<double> log_std;  // (action_dim)
  PpoNetworks(int observation_dim, int action_dim, const PpoConfig& cfg);
  std::size_t param_count() const { return policy.param_count() + value.param_count() + log_std.size(); }
  void init(const PpoConfig& cfg, Rng& rng);  // SB3's orthogonal init, log_std = log_std_init
};

// GAE (Schulman et al. 2016) over one rollout of n decisions, in reverse:
//   delta_t = r_t + gamma V_{t+1} (1 - done_t) - V_t,  A_t = delta_t + gamma lambda (1 - done_t) A_{t+1}
// where V_{t+1} is values[t + 1], or last_value after the last decision (the value of the
// observation the rollout stopped at); done_t = 1 when decision t ended its episode. returns =
// A + V (SB3's value targets). All spans (n).
void compute_gae(std::span<const double> rewards, std::span<const double> values, std::span<const double> dones,
                 double last_value, double gamma, double lambda, std::span<double> advantages,
                 std::span<double> returns);

// A minibatch of B decisions.
struct PpoBatch {
  Eigen::MatrixXd observations;                           // (observation_dim x B)
  Eigen::MatrixXd actions;                                // (action_dim x B), as sampled (unclipped)
  std::vector<double> old_log_prob, advantages, returns;  // (B)
};

struct PpoLoss {
  double loss = 0.0, policy_loss = 0.0, value_loss = 0.0, entropy_loss = 0.0;
  double clip_fraction = 0.0;  // share of the batch with |ratio - 1| > clip_range
  double approx_kl = 0.0;      // mean((ratio - 1) - log ratio), SB3's estimate
};

// SB3's PPO loss on one minibatch at the networks' current parameters:
//   A' = (A - mean A) / (std A + 1e-8);  ratio = exp(log pi(a|s) - old log pi)
//   L = -mean(min(ratio A', clip(ratio, 1 - c, 1 + c) A')) + ent_coef (-mean entropy)
//       + vf_coef mean((returns - V(s))^2)
// and ADDS dL/dparams (PpoNetworks' flat order) to grad (param_count()).
PpoLoss ppo_loss(const PpoNetworks& nets, const PpoBatch& batch, const PpoConfig& cfg, std::span<double> grad);

std::unique_ptr<Optimizer> make_ppo(PpoConfig cfg = {});

}  // namespace dsb
