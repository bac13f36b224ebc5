#include "optimizers/rl/ppo.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/config_fields.hpp"
#include "common/det_math.hpp"
#include "common/field_check.hpp"
#include "common/number_text.hpp"
#include "optimizers/core/configured_optimizer.hpp"
#include "optimizers/rl/gaussian.hpp"
#include "optimizers/rl/network_adam.hpp"
#include "optimizers/rl/rl_core.hpp"

namespace dsb {

void PpoConfig::validate() const {
  const FieldCheck check("ppo");
  check.require(std::isfinite(learning_rate) && learning_rate > 0.0, "learning_rate",
                "must be > 0, got " + number_text(learning_rate));
  check.require(n_steps >= 1, "n_steps", "must be >= 1, got " + std::to_string(n_steps));
  check.require(batch_size >= 1 && batch_size <= n_steps, "batch_size",
                "must be in 1..n_steps, got " + std::to_string(batch_size));
  check.require(n_epochs >= 1, "n_epochs", "must be >= 1, got " + std::to_string(n_epochs));
  check.require(gamma >= 0.0 && gamma <= 1.0, "gamma", "must be in [0, 1], got " + number_text(gamma));
  check.require(gae_lambda >= 0.0 && gae_lambda <= 1.0, "gae_lambda",
                "must be in [0, 1], got " + number_text(gae_lambda));
  check.require(std::isfinite(clip_range) && clip_range > 0.0, "clip_range",
                "must be > 0, got " + number_text(clip_range));
  check.require(std::isfinite(ent_coef) && ent_coef >= 0.0, "ent_coef", "must be >= 0, got " + number_text(ent_coef));
  check.require(std::isfinite(vf_coef) && vf_coef >= 0.0, "vf_coef", "must be >= 0, got " + number_text(vf_coef));
  check.require(std::isfinite(max_grad_norm) && max_grad_norm > 0.0, "max_grad_norm",
                "must be > 0, got " + number_text(max_grad_norm));
  check.require(std::isfinite(adam_eps) && adam_eps > 0.0, "adam_eps", "must be > 0, got " + number_text(adam_eps));
  check.require(std::isfinite(log_std_init), "log_std_init", "must be finite, got " + number_text(log_std_init));
  check.require(!hidden.empty() && std::all_of(hidden.begin(), hidden.end(), [](int h) { return h >= 1; }), "hidden",
                "must be one or more layer widths >= 1");
  failed_loss.validate("ppo");
}

nlohmann::json PpoConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["activation"] = "tanh";
  j["networks"] = "separate policy and value MLPs";
  j["reward"] = "sparse: -episode loss at the last decision; failed episode: -2 x largest finite loss so far";
  // the failed-episode loss enters only when it is not the default, so the default config (and
  // every run key made with it) is the one it always was
  const FailedEpisodeLoss standard = PpoConfig{}.failed_loss;
  if (failed_loss.factor != standard.factor || failed_loss.floor != standard.floor ||
      failed_loss.before_any != standard.before_any) {
    j["failed_loss_factor"] = failed_loss.factor;
    j["failed_loss_floor"] = failed_loss.floor;
    j["failed_loss_before_any"] = failed_loss.before_any;
  }
  return j;
}

PpoNetworks::PpoNetworks(int observation_dim, int action_dim, const PpoConfig& cfg)
    : policy(mlp_layer_sizes(observation_dim, cfg.hidden, action_dim), Activation::tanh),
      value(mlp_layer_sizes(observation_dim, cfg.hidden, 1), Activation::tanh),
      log_std(static_cast<std::size_t>(action_dim), cfg.log_std_init) {}

void PpoNetworks::init(const PpoConfig& cfg, Rng& rng) {
  // SB3 ortho_init: hidden layers gain sqrt(2), action head 0.01, value head 1, biases 0
  init_orthogonal(policy, 0.01, rng);
  init_orthogonal(value, 1.0, rng);
  std::fill(log_std.begin(), log_std.end(), cfg.log_std_init);
}

void compute_gae(std::span<const double> rewards, std::span<const double> values, std::span<const double> dones,
                 double last_value, double gamma, double lambda, std::span<double> advantages,
                 std::span<double> returns) {
  const std::size_t n = rewards.size();
  if (values.size() != n || dones.size() != n || advantages.size() != n || returns.size() != n)
    throw std::invalid_argument("compute_gae: spans of different sizes");
  double next_advantage = 0.0;
  for (std::size_t k = n; k-- > 0;) {
    // delta_t = r_t + gamma V_{t+1} (1 - done_t) - V_t; A_t = delta_t + gamma lambda (1 - done_t) A_{t+1}
    const double next_value = k + 1 < n ? values[k + 1] : last_value;
    const double live = 1.0 - dones[k];
    const double delta = rewards[k] + gamma * next_value * live - values[k];
    next_advantage = delta + gamma * lambda * live * next_advantage;
    advantages[k] = next_advantage;
    returns[k] = next_advantage + values[k];
  }
}

PpoLoss ppo_loss(const PpoNetworks& nets, const PpoBatch& batch, const PpoConfig& cfg, std::span<double> grad) {
  const int B = static_cast<int>(batch.actions.cols());
  const int A = static_cast<int>(batch.actions.rows());
  const std::size_t np = nets.policy.param_count(), nv = nets.value.param_count();
  if (grad.size() != nets.param_count()) throw std::invalid_argument("ppo_loss: gradient of the wrong size");
  MlpCache pc, vc;
  const Eigen::MatrixXd mean = nets.policy.forward(batch.observations, &pc);  // (A x B)
  const Eigen::MatrixXd v = nets.value.forward(batch.observations, &vc);      // (1 x B)

  // per-minibatch advantage normalisation, std with Bessel's correction (torch.std); SB3 skips it
  // for a single sample
  std::vector<double> adv(batch.advantages);
  if (B > 1) {
    double m = 0.0;
    for (double a : adv) m += a;
    m /= B;
    double ss = 0.0;
    for (double a : adv) ss += (a - m) * (a - m);
    const double sd = std::sqrt(ss / (B - 1));
    for (double& a : adv) a = (a - m) / (sd + 1e-8);
  }

  PpoLoss out;
  Eigen::MatrixXd d_mean(A, B), d_v(1, B);
  std::vector<double> d_log_std(A, 0.0), dm_i(A), dls_i(A);
  const double c = cfg.clip_range;
  for (int i = 0; i < B; ++i) {
    const std::span<const double> a(batch.actions.col(i).data(), A), mu(mean.col(i).data(), A);
    const double logp = diag_gaussian_log_prob(a, mu, nets.log_std, dm_i, dls_i);
    const double log_ratio = logp - batch.old_log_prob[i];
    const double ratio = dm::exp(log_ratio);
    // clipped surrogate: -min(ratio A, clip(ratio, 1 - c, 1 + c) A)
    const double unclipped = ratio * adv[i];
    const double clipped = std::clamp(ratio, 1.0 - c, 1.0 + c) * adv[i];
    out.policy_loss -= std::min(unclipped, clipped) / B;
    // d/dratio: -A where the unclipped term is the min (inside the range both terms are the same
    // function of ratio), 0 where the clipped constant is
    const double d_ratio = unclipped <= clipped ? -adv[i] / B : 0.0;
    const double d_logp = d_ratio * ratio;
    for (int k = 0; k < A; ++k) {
      d_mean(k, i) = d_logp * dm_i[k];
      d_log_std[k] += d_logp * dls_i[k];
    }
    out.clip_fraction += (std::abs(ratio - 1.0) > c ? 1.0 : 0.0) / B;
    out.approx_kl += ((ratio - 1.0) - log_ratio) / B;
    // value: vf_coef mean((R - V)^2)
    const double err = v(0, i) - batch.returns[i];
    out.value_loss += err * err / B;
    d_v(0, i) = cfg.vf_coef * 2.0 * err / B;
  }
  // entropy bonus: ent_coef (-mean entropy); the entropy does not depend on the state
  std::vector<double> d_entropy(A, 0.0);
  out.entropy_loss = -diag_gaussian_entropy(nets.log_std, d_entropy);
  for (int k = 0; k < A; ++k) d_log_std[k] -= cfg.ent_coef * d_entropy[k];
  out.loss = out.policy_loss + cfg.ent_coef * out.entropy_loss + cfg.vf_coef * out.value_loss;

  nets.policy.backward(pc, d_mean, grad.subspan(0, np));
  nets.value.backward(vc, d_v, grad.subspan(np, nv));
  for (int k = 0; k < A; ++k) grad[np + nv + k] += d_log_std[k];
  return out;
}

namespace {

class Ppo : public ConfiguredOptimizer<PpoConfig> {
 public:
  explicit Ppo(PpoConfig cfg) : ConfiguredOptimizer("ppo", false, std::move(cfg)) {}
  nlohmann::json diagnostics() const override { return diag_; }

  void minimize(Objective& f, Rng& rng) override {
    require_rl_view(f, name_);
    diag_ = nlohmann::json::object();
    episodes_ = EpisodeLosses(cfg_.failed_loss, kBlock);
    updates_ = 0;
    obs_sanitized_ = 0;
    last_ = {};
    const RlSpec spec = f.rl_spec();
    const int O = spec.observation_dim, A = spec.action_dim, N = cfg_.n_steps;
    PpoNetworks nets(O, A, cfg_);
    nets.init(cfg_, rng);
    AdamConfig adam{cfg_.learning_rate, 0.9, 0.999, cfg_.adam_eps};
    // one Adam over [policy | value | log_std]: Adam is elementwise, so three with one step count are one
    NetworkAdam adam_pi(adam, nets.policy.param_count()), adam_v(adam, nets.value.param_count()),
        adam_ls(adam, nets.log_std.size());

    // rollout storage (N decisions)
    Eigen::MatrixXd obs_buf(O, N), act_buf(A, N);
    std::vector<double> logp_buf(N), value_buf(N), reward_buf(N), done_buf(N), adv(N), ret(N);
    std::vector<double> obs(O), next_obs(O), mean(A), action(A), clipped(A);
    std::vector<double> grad(nets.param_count());
    std::vector<int> order(N);
    PpoBatch batch;
    bool open = false;
    try {
      for (;;) {
        // collect N decisions; episodes run on across rollouts
        for (int t = 0; t < N; ++t) {
          if (!open) {
            f.rl_reset(obs);
            obs_sanitized_ += sanitize_observation(obs);
            open = true;
          }
          const Eigen::Map<const Eigen::VectorXd> o(obs.data(), O);
          obs_buf.col(t) = o;
          const Eigen::VectorXd mu = nets.policy.forward_one(o);
          value_buf[t] = nets.value.forward_one(o)(0);
          diag_gaussian_sample(std::span<const double>(mu.data(), A), nets.log_std, rng, action);
          logp_buf[t] = diag_gaussian_log_prob(action, std::span<const double>(mu.data(), A), nets.log_std);
          for (int k = 0; k < A; ++k) {
            act_buf(k, t) = action[k];
            clipped[k] = std::clamp(action[k], -1.0, 1.0);
          }
          const RlStep step = f.rl_step(clipped, next_obs);
          obs_sanitized_ += sanitize_observation(next_obs);
          // sparse reward: -loss at the last decision (a failed episode's stand-in: rl_core.hpp)
          reward_buf[t] = step.done ? -episodes_.finish_episode(step.loss) : 0.0;
          done_buf[t] = step.done ? 1.0 : 0.0;
          if (step.done) open = false;
          obs.swap(next_obs);
        }
        // the value of where the rollout stopped (unused after a finished episode)
        const double last_value =
            open ? nets.value.forward_one(Eigen::Map<const Eigen::VectorXd>(obs.data(), O))(0) : 0.0;
        compute_gae(reward_buf, value_buf, done_buf, last_value, cfg_.gamma, cfg_.gae_lambda, adv, ret);
        update(nets, adam_pi, adam_v, adam_ls, obs_buf, act_buf, logp_buf, adv, ret, order, grad, batch, rng);
      }
    } catch (const BudgetExhausted&) {
      finish(nets);
      throw;
    }
  }

 private:
  void update(PpoNetworks& nets, NetworkAdam& adam_pi, NetworkAdam& adam_v, NetworkAdam& adam_ls,
              const Eigen::MatrixXd& obs_buf, const Eigen::MatrixXd& act_buf, const std::vector<double>& logp_buf,
              const std::vector<double>& adv, const std::vector<double>& ret, std::vector<int>& order,
              std::vector<double>& grad, PpoBatch& batch, Rng& rng) {
    const int N = cfg_.n_steps, O = static_cast<int>(obs_buf.rows()), A = static_cast<int>(act_buf.rows());
    const std::size_t np = nets.policy.param_count(), nv = nets.value.param_count();
    PpoLoss last;
    for (int epoch = 0; epoch < cfg_.n_epochs; ++epoch) {
      // a fresh permutation per epoch (Fisher-Yates on our Rng), minibatches in its order; the
      // last one is shorter when batch_size does not divide n_steps (as SB3)
      for (int i = 0; i < N; ++i) order[i] = i;
      for (int i = N - 1; i > 0; --i) std::swap(order[i], order[rng.below(static_cast<std::uint64_t>(i) + 1)]);
      for (int start = 0; start < N; start += cfg_.batch_size) {
        const int B = std::min(cfg_.batch_size, N - start);
        batch.observations.resize(O, B);
        batch.actions.resize(A, B);
        batch.old_log_prob.resize(B);
        batch.advantages.resize(B);
        batch.returns.resize(B);
        for (int b = 0; b < B; ++b) {
          const int j = order[start + b];
          batch.observations.col(b) = obs_buf.col(j);
          batch.actions.col(b) = act_buf.col(j);
          batch.old_log_prob[b] = logp_buf[j];
          batch.advantages[b] = adv[j];
          batch.returns[b] = ret[j];
        }
        std::fill(grad.begin(), grad.end(), 0.0);
        last = ppo_loss(nets, batch, cfg_, grad);
        clip_grad_norm(grad, cfg_.max_grad_norm);
        const std::span<double> g(grad);
        adam_pi.step(nets.policy.params(), g.subspan(0, np));
        adam_v.step(nets.value.params(), g.subspan(np, nv));
        adam_ls.step(nets.log_std, g.subspan(np + nv));
      }
    }
    ++updates_;
    last_ = last;
  }

  void finish(const PpoNetworks& nets) {
    episodes_.put_diagnostics(diag_);
    diag_["updates"] = updates_;
    diag_["observations_sanitized"] = obs_sanitized_;
    diag_["policy_hash"] = params_digest({nets.policy.params(), nets.value.params(), nets.log_std});
    diag_["log_std"] = nets.log_std;
    diag_["last_update"] = {{"policy_loss", last_.policy_loss},
                            {"value_loss", last_.value_loss},
                            {"clip_fraction", last_.clip_fraction},
                            {"approx_kl", last_.approx_kl}};
  }

  static constexpr int kBlock = 20;  // episodes per point of the learning curve
  nlohmann::json diag_ = nlohmann::json::object();
  EpisodeLosses episodes_{FailedEpisodeLoss{}, kBlock};
  std::int64_t updates_ = 0, obs_sanitized_ = 0;  // observations clamped to +-1e6 or NaN set to 0 (rl_core.hpp)
  PpoLoss last_;
};

}  // namespace

std::unique_ptr<Optimizer> make_ppo(PpoConfig cfg) { return std::make_unique<Ppo>(std::move(cfg)); }

}  // namespace dsb
