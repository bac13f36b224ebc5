#include "optimizers/rl/sac.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/config_fields.hpp"
#include "common/det_math.hpp"
#include "common/field_check.hpp"
#include "common/number_text.hpp"
#include "common/rng.hpp"
#include "optimizers/core/configured_optimizer.hpp"
#include "optimizers/core/diagnostics.hpp"
#include "optimizers/rl/network_adam.hpp"
#include "optimizers/rl/replay_buffer.hpp"
#include "optimizers/rl/rl_core.hpp"

namespace dsb {
namespace {

class Sac : public ConfiguredOptimizer<SacConfig> {
 public:
  explicit Sac(const SacConfig& cfg) : ConfiguredOptimizer("sac", false, cfg) {}
  nlohmann::json diagnostics() const override;
  void minimize(Objective& f, Rng& rng) override;

 private:
  void train(Rng& rng, int gradient_steps);

  // run state (rebuilt by minimize)
  int obs_dim_ = 0, act_dim_ = 0;
  std::unique_ptr<Mlp> actor_;
  std::vector<Mlp> critics_, targets_;
  std::unique_ptr<NetworkAdam> actor_adam_, alpha_adam_;
  std::vector<NetworkAdam> critic_adams_;
  std::unique_ptr<ReplayBuffer> buffer_;
  ReplayBatch batch_;
  double log_alpha_ = 0.0, target_entropy_ = 0.0;
  std::vector<double> actor_grad_;
  std::vector<std::vector<double>> critic_grads_;

  // diagnostics
  EpisodeLosses episodes_{FailedEpisodeLoss{}, 1};
  std::int64_t timesteps_ = 0, gradient_steps_ = 0, obs_sanitized_ = 0;
  double last_critic_loss_ = NAN, last_actor_loss_ = NAN, last_alpha_loss_ = NAN;
  std::size_t buffer_capacity_ = 0;
};

void Sac::minimize(Objective& f, Rng& rng) {
  // reset everything a previous run left
  timesteps_ = gradient_steps_ = obs_sanitized_ = 0;
  episodes_ = EpisodeLosses(cfg_.failed_loss(), 1);
  last_critic_loss_ = last_actor_loss_ = last_alpha_loss_ = NAN;
  actor_.reset();
  critics_.clear();
  targets_.clear();
  buffer_.reset();
  buffer_capacity_ = 0;

  require_rl_view(f, name_);
  const RlSpec spec = f.rl_spec();
  obs_dim_ = spec.observation_dim;
  act_dim_ = spec.action_dim;
  if (obs_dim_ < 1 || act_dim_ < 1 || spec.decisions < 1)
    throw std::logic_error("sac: RL spec with an empty observation, action or episode");

  // networks: actor (mean, log_std), n critics; torch default init in that order; targets = copies
  actor_ = std::make_unique<Mlp>(mlp_layer_sizes(obs_dim_, cfg_.net_arch, 2 * act_dim_), Activation::relu);
  init_torch_default(*actor_, rng);
  for (int k = 0; k < cfg_.n_critics; ++k) {
    critics_.emplace_back(mlp_layer_sizes(obs_dim_ + act_dim_, cfg_.net_arch, 1), Activation::relu);
    init_torch_default(critics_.back(), rng);
  }
  targets_ = critics_;
  AdamConfig adam;
  adam.lr = cfg_.learning_rate;
  adam.eps = cfg_.adam_eps;
  actor_adam_ = std::make_unique<NetworkAdam>(adam, actor_->param_count());
  critic_adams_.clear();
  for (const auto& c : critics_) critic_adams_.emplace_back(adam, c.param_count());
  alpha_adam_ = std::make_unique<NetworkAdam>(adam, 1);
  actor_grad_.assign(actor_->param_count(), 0.0);
  critic_grads_.assign(critics_.size(), std::vector<double>(critics_[0].param_count(), 0.0));
  log_alpha_ = dm::log(cfg_.ent_coef_init);
  target_entropy_ = -static_cast<double>(act_dim_);

  // buffer: bounded by what the remaining budget can fill
  const std::int64_t remaining = std::max<std::int64_t>(f.remaining(), 1);
  const std::int64_t can_fill =
      remaining > cfg_.buffer_size / spec.decisions ? cfg_.buffer_size : remaining * spec.decisions;
  buffer_capacity_ = static_cast<std::size_t>(std::min(cfg_.buffer_size, std::max<std::int64_t>(can_fill, 1)));
  buffer_ = std::make_unique<ReplayBuffer>(buffer_capacity_, obs_dim_, act_dim_);
  // the learning curve: at most kDiagnosticsListCap blocks over the remaining budget
  episodes_ = EpisodeLosses(cfg_.failed_loss(),
                            (remaining + std::int64_t(kDiagnosticsListCap) - 1) / std::int64_t(kDiagnosticsListCap));

  std::vector<double> obs(obs_dim_), next_obs(obs_dim_), action(act_dim_);
  Eigen::VectorXd x(obs_dim_);
  // until rl_reset throws BudgetExhausted
  for (;;) {
    f.rl_reset(obs);
    obs_sanitized_ += sanitize_observation(obs);
    for (;;) {
      // SB3 _sample_action: uniform while num_timesteps < learning_starts, else a policy sample
      if (timesteps_ < cfg_.learning_starts) {
        for (double& a : action) a = rng.uniform(-1.0, 1.0);
      } else {
        for (int i = 0; i < obs_dim_; ++i) x[i] = obs[i];
        const Eigen::VectorXd out = actor_->forward_one(x);
        const SquashedGaussian g =
            squashed_gaussian_sample(std::span<const double>(out.data(), act_dim_),
                                     std::span<const double>(out.data() + act_dim_, act_dim_), rng);
        for (int i = 0; i < act_dim_; ++i) action[i] = g.a[i];
        for (double a : action)
          if (!(a >= -1.0 && a <= 1.0)) throw std::runtime_error("sac: the policy diverged (non-finite action)");
      }
      const RlStep st = f.rl_step(action, next_obs);
      ++timesteps_;
      obs_sanitized_ += sanitize_observation(next_obs);
      double reward = 0.0;
      if (st.done) {
        // sparse reward: -loss at the final decision (a failed episode's stand-in: rl_core.hpp)
        reward = -episodes_.finish_episode(st.loss);
      }
      // the episode's end is terminal: done = 1, no bootstrap past the final loss
      buffer_->add(obs, action, reward, next_obs, st.done);
      if (timesteps_ > cfg_.learning_starts && timesteps_ % cfg_.train_freq == 0) train(rng, cfg_.gradient_steps);
      obs.swap(next_obs);
      if (st.done) break;
    }
  }
}

void Sac::train(Rng& rng, int gradient_steps) {
  const int n = cfg_.batch_size;
  Eigen::MatrixXd eps(act_dim_, n), eps_next(act_dim_, n);
  std::vector<double> y(n);
  for (int step = 0; step < gradient_steps; ++step) {
    buffer_->sample(n, rng, batch_);
    // fresh actor sample at s; alpha before its update
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < act_dim_; ++i) eps(i, j) = rng.normal();
    const SacActorPass pi = sac_actor_pass(*actor_, batch_.obs, eps);
    const double alpha = dm::exp(log_alpha_);
    // entropy coefficient
    const double g_alpha = sac_alpha_loss_grad(pi.log_prob, target_entropy_);
    last_alpha_loss_ = log_alpha_ * g_alpha;
    alpha_adam_->step(std::span<double>(&log_alpha_, 1), std::span<const double>(&g_alpha, 1));
    // critic target from the current actor at s' and the target critics
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < act_dim_; ++i) eps_next(i, j) = rng.normal();
    const SacActorPass next = sac_actor_pass(*actor_, batch_.next_obs, eps_next);
    const std::vector<double> min_q = sac_min_q(targets_, batch_.next_obs, next.actions);
    for (int j = 0; j < n; ++j)
      y[j] = sac_critic_target(batch_.reward[j], batch_.done[j], cfg_.gamma, min_q[j], alpha, next.log_prob[j]);
    // critics
    for (auto& g : critic_grads_) std::fill(g.begin(), g.end(), 0.0);
    last_critic_loss_ = sac_critic_loss(critics_, batch_.obs, batch_.action, y, &critic_grads_);
    for (std::size_t k = 0; k < critics_.size(); ++k) critic_adams_[k].step(critics_[k].params(), critic_grads_[k]);
    // actor, on the updated critics
    std::fill(actor_grad_.begin(), actor_grad_.end(), 0.0);
    last_actor_loss_ = sac_actor_loss(*actor_, pi, critics_, batch_.obs, alpha, actor_grad_);
    actor_adam_->step(actor_->params(), actor_grad_);
    // target critics
    if (step % cfg_.target_update_interval == 0)
      for (std::size_t k = 0; k < critics_.size(); ++k)
        polyak_update(targets_[k].params(), critics_[k].params(), cfg_.tau);
    ++gradient_steps_;
  }
}

nlohmann::json Sac::diagnostics() const {
  nlohmann::json d = {
      {"timesteps", timesteps_},
      {"gradient_steps", gradient_steps_},
      {"buffer_capacity", buffer_capacity_},
      {"observations_sanitized", obs_sanitized_},
      {"alpha", actor_ ? nlohmann::json(dm::exp(log_alpha_)) : nlohmann::json(nullptr)},
      {"target_entropy", target_entropy_},
      {"last_critic_loss",
       std::isfinite(last_critic_loss_) ? nlohmann::json(last_critic_loss_) : nlohmann::json(nullptr)},
      {"last_actor_loss", std::isfinite(last_actor_loss_) ? nlohmann::json(last_actor_loss_) : nlohmann::json(nullptr)},
      {"last_alpha_loss", std::isfinite(last_alpha_loss_) ? nlohmann::json(last_alpha_loss_) : nlohmann::json(nullptr)},
      {"policy_hash", actor_ ? nlohmann::json(params_digest({actor_->params()})) : nlohmann::json(nullptr)}};
  episodes_.put_diagnostics(d);
  return d;
}

}  // namespace

void SacConfig::validate() const {
  const FieldCheck check("sac");
  check.number_above("learning_rate", learning_rate, 0.0);
  check.number_above("adam_eps", adam_eps, 0.0);
  check.require(buffer_size >= 1, "buffer_size", "must be >= 1 (got " + std::to_string(buffer_size) + ")");
  check.require(learning_starts >= 0, "learning_starts", "must be >= 0 (got " + std::to_string(learning_starts) + ")");
  check.require(batch_size >= 1, "batch_size", "must be >= 1 (got " + std::to_string(batch_size) + ")");
  check.require(tau > 0.0 && tau <= 1.0, "tau", "must lie in (0, 1] (got " + number_text(tau) + ")");
  check.require(gamma >= 0.0 && gamma <= 1.0, "gamma", "must lie in [0, 1] (got " + number_text(gamma) + ")");
  check.require(train_freq >= 1, "train_freq", "must be >= 1 (got " + std::to_string(train_freq) + ")");
  check.require(gradient_steps >= 1, "gradient_steps", "must be >= 1 (got " + std::to_string(gradient_steps) + ")");
  check.require(target_update_interval >= 1, "target_update_interval",
                "must be >= 1 (got " + std::to_string(target_update_interval) + ")");
  check.require(n_critics >= 1, "n_critics", "must be >= 1 (got " + std::to_string(n_critics) + ")");
  check.require(!net_arch.empty(), "net_arch", "must list at least one hidden layer");
  for (int h : net_arch) check.require(h >= 1, "net_arch", "layer sizes must be >= 1 (got " + std::to_string(h) + ")");
  check.number_above("ent_coef_init", ent_coef_init, 0.0);
  // the floor is also the stand-in before any finite loss, so it must be > 0
  check.number_above("failed_loss_floor", failed_loss_floor, 0.0);
  failed_loss().validate("sac");
}

nlohmann::json SacConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["activation"] = "relu";
  j["ent_coef"] = "auto";
  j["target_entropy"] = "-action_dim";
  j["log_std_clamp"] = {kSacLogStdMin, kSacLogStdMax};
  j["reward"] = "sparse: -loss at the final decision";
  j["episode_end"] = "terminal (done = 1, no bootstrap)";
  return j;
}

std::unique_ptr<Optimizer> make_sac(const SacConfig& cfg) { return std::make_unique<Sac>(cfg); }

}  // namespace dsb
