// `ppo` (optimizers/rl/ppo.hpp): GAE on a hand-computed trajectory, the PPO loss gradient against
// central differences on a fixed minibatch, learning on the test reach env against random search,
// the budget, identical reruns, config validation; and both RL optimizers (ppo, sac) through the
// harness program: the same results for --jobs 1 and 2, paired only with RL envs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "harness/run/budget.hpp"
#include "optimizers/registry.hpp"
#include "optimizers/rl/gaussian.hpp"
#include "optimizers/rl/ppo.hpp"
#include "support/config_error.hpp"
#include "support/gradient_vs_differences.hpp"
#include "support/harness_process.hpp"
#include "tests/support/reach_env.hpp"

namespace dsb {
namespace {

TEST(PpoGae, FourStepsByHand) {
  // decisions 0..3; the episode ends at decision 1 (terminal), a new one runs 2..3 and is cut
  // by the rollout's end, bootstrapped with last_value
  const std::vector<double> r = {0.0, -1.0, 0.0, 0.5}, v = {0.2, -0.4, 0.1, 0.3}, done = {0, 1, 0, 0};
  const double last_value = 0.6, g = 0.9, l = 0.8;
  std::vector<double> adv(4), ret(4);
  compute_gae(r, v, done, last_value, g, l, adv, ret);
  // by hand, backwards
  const double d3 = 0.5 + g * 0.6 - 0.3;  // 0.74
  const double a3 = d3;
  const double d2 = 0.0 + g * 0.3 - 0.1;     // 0.17
  const double a2 = d2 + g * l * a3;         // 0.17 + 0.72 * 0.74 = 0.7028
  const double d1 = -1.0 - (-0.4);           // terminal: -0.6
  const double a1 = d1;                      // nothing flows back across the episode's end
  const double d0 = 0.0 + g * (-0.4) - 0.2;  // -0.56
  const double a0 = d0 + g * l * a1;         // -0.56 - 0.432 = -0.992
  const double want[4] = {a0, a1, a2, a3};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(adv[k], want[k], 1e-15) << k;
    EXPECT_NEAR(ret[k], want[k] + v[k], 1e-15) << k;
  }
  EXPECT_NEAR(adv[0], -0.992, 1e-15);
  EXPECT_NEAR(adv[2], 0.7028, 1e-15);
}

// a fixed minibatch on default-shaped networks (3 x 64): old log-probs offset so that some ratios
// sit well inside the clip range and some well outside, on both sides
struct Fixture {
  PpoConfig cfg;
  PpoNetworks nets{3, 2, cfg};
  PpoBatch batch;
  Fixture() {
    cfg.ent_coef = 0.01;  // exercise the entropy term's gradient too
    Rng rng(11);
    nets.init(cfg, rng);
    // move the networks off their init (a head of gain 0.01 makes every mean ~0)
    for (double& p : nets.policy.params()) p += 0.05 * rng.normal();
    for (double& p : nets.value.params()) p += 0.05 * rng.normal();
    nets.log_std = {-0.3, 0.2};
    const int B = 16;
    batch.observations.resize(3, B);
    batch.actions.resize(2, B);
    batch.old_log_prob.resize(B);
    batch.advantages.resize(B);
    batch.returns.resize(B);
    for (int i = 0; i < B; ++i) {
      for (int k = 0; k < 3; ++k) batch.observations(k, i) = rng.uniform(-1.0, 1.0);
      for (int k = 0; k < 2; ++k) batch.actions(k, i) = rng.uniform(-1.5, 1.5);
      const Eigen::VectorXd mu = nets.policy.forward_one(batch.observations.col(i));
      const double logp = diag_gaussian_log_prob(std::span<const double>(batch.actions.col(i).data(), 2),
                                                 std::span<const double>(mu.data(), 2), nets.log_std);
      const double offsets[4] = {0.05, -0.04, 0.5, -0.6};  // ratios 0.95, 1.04 (inside), 0.61, 1.82 (outside)
      batch.old_log_prob[i] = logp + offsets[i % 4];
      batch.advantages[i] = rng.uniform(-2.0, 2.0);
      batch.returns[i] = rng.uniform(-1.0, 1.0);
    }
  }
  double loss_at(std::span<const double> flat) {
    PpoNetworks n = nets;
    set(n, flat);
    std::vector<double> g(n.param_count());
    return ppo_loss(n, batch, cfg, g).loss;
  }
  static void set(PpoNetworks& n, std::span<const double> flat) {
    const std::size_t np = n.policy.param_count(), nv = n.value.param_count();
    std::copy(flat.begin(), flat.begin() + np, n.policy.params().begin());
    std::copy(flat.begin() + np, flat.begin() + np + nv, n.value.params().begin());
    std::copy(flat.begin() + np + nv, flat.end(), n.log_std.begin());
  }
  std::vector<double> flat() const {
    std::vector<double> f(nets.policy.params().begin(), nets.policy.params().end());
    f.insert(f.end(), nets.value.params().begin(), nets.value.params().end());
    f.insert(f.end(), nets.log_std.begin(), nets.log_std.end());
    return f;
  }
};

TEST(PpoLossTest, GradientMatchesCentralDifferencesOnAFixedBatch) {
  Fixture fx;
  std::vector<double> grad(fx.nets.param_count(), 0.0);
  const PpoLoss l = ppo_loss(fx.nets, fx.batch, fx.cfg, grad);
  std::printf("ppo loss %.6f (policy %.6f, value %.6f, entropy %.6f), clip fraction %.3f, approx kl %.4f\n", l.loss,
              l.policy_loss, l.value_loss, l.entropy_loss, l.clip_fraction, l.approx_kl);
  EXPECT_NEAR(l.clip_fraction, 0.5, 1e-12);  // the offsets put half the batch outside the range
  EXPECT_NEAR(l.loss, l.policy_loss + 0.01 * l.entropy_loss + 0.5 * l.value_loss, 1e-15);
  // every coordinate of the policy head and log_std, every 7th of the others
  auto x = fx.flat();
  const std::size_t np = fx.nets.policy.param_count(), nv = fx.nets.value.param_count();
  const std::size_t policy_head = fx.nets.policy.weight_offset(fx.nets.policy.layer_count() - 1);
  double worst = 0.0, max_abs = 0.0, err2 = 0.0, ref2 = 0.0;
  int checked = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const bool dense = (i >= policy_head && i < np) || i >= np + nv;
    if (!dense && i % 7 != 0) continue;
    const double fd = testing::central_difference(x[i], 1e-6, [&] { return fx.loss_at(x); });
    err2 += (grad[i] - fd) * (grad[i] - fd);
    ref2 += fd * fd;
    max_abs = std::max(max_abs, std::abs(fd));
    worst = std::max(worst, std::abs(grad[i] - fd));
    ++checked;
  }
  const double normwise = std::sqrt(err2 / ref2);
  std::printf(
      "ppo loss gradient vs central differences (h 1e-6) over %d of %zu params: normwise %.2e, worst "
      "|error| %.2e of max |fd| %.2e\n",
      checked, x.size(), normwise, worst, max_abs);
  // rounding of (up - down) / 2h: eps |L| / h ~ 2e-10 per coordinate; truncation h^2 |L'''| tiny
  EXPECT_LT(normwise, 1e-6);
  EXPECT_LT(worst, 1e-6 * max_abs + 1e-9);
  // the log-std gradients are nonzero (ent_coef and the surrogate both reach them)
  EXPECT_NE(grad[np + nv], 0.0);
}

double best_of(const Env& env, std::int64_t budget, const std::string& optimizer, std::uint64_t seed,
               nlohmann::json* diagnostics = nullptr, std::vector<double>* losses = nullptr) {
  BudgetedObjective f(env, budget);
  auto opt = optimizer == "ppo" ? make_ppo() : make_optimizer(optimizer);
  Rng rng(seed);
  try {
    opt->minimize(f, rng);
  } catch (const BudgetExhausted&) {}
  EXPECT_EQ(f.used(), budget) << optimizer;
  if (diagnostics) *diagnostics = opt->diagnostics();
  if (losses)
    for (const auto& e : f.evals()) losses->push_back(e.loss);
  return f.best_loss();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

TEST(PpoLearning, BeatsRandomSearchOnTheReachEnv) {
  // 1,000 episodes of 20 decisions = 20,000 decisions, 9 PPO updates of 2,048
  testing::ReachEnv env;
  std::vector<double> ppo, random;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    nlohmann::json d;
    ppo.push_back(best_of(env, 1000, "ppo", seed, &d));
    random.push_back(best_of(env, 1000, "random", seed));
    std::printf("seed %llu: ppo best %.4g (updates %d, log_std %s, last block mean loss %s), random best %.4g\n",
                static_cast<unsigned long long>(seed), ppo.back(), d["updates"].get<int>(), d["log_std"].dump().c_str(),
                d["mean_loss_per_block"].back().dump().c_str(), random.back());
  }
  std::printf("reach env, 1,000 episodes, 5 seeds: median best loss ppo %.4g, random %.4g\n", median(ppo),
              median(random));
  EXPECT_LT(median(ppo), median(random));
}

// The reach env observed through a lens that multiplies the position by 1e12: finite, but far past
// the +-1e6 that the RL optimizers clamp observations to (rl_core.hpp sanitize_observation).
class HugeObservationReach : public Env {
 public:
  HugeObservationReach() : Env(testing::ReachEnv().info()) {}
  nlohmann::json config() const override { return inner_.config(); }
  class Rl : public RlEnv {
   public:
    explicit Rl(std::unique_ptr<RlEnv> inner) : inner_(std::move(inner)) {}
    int observation_dim() const override { return inner_->observation_dim(); }
    int action_dim() const override { return inner_->action_dim(); }
    int horizon() const override { return inner_->horizon(); }
    int action_repeat() const override { return inner_->action_repeat(); }
    void reset() override { inner_->reset(); }
    std::vector<double> observe() const override {
      std::vector<double> o = inner_->observe();
      o[0] *= 1e12;
      return o;
    }
    void step(std::span<const double> a) override { inner_->step(a); }
    bool done() const override { return inner_->done(); }
    double final_loss() const override { return inner_->final_loss(); }

   private:
    std::unique_ptr<RlEnv> inner_;
  };
  std::unique_ptr<RlEnv> make_rl() const override { return std::make_unique<Rl>(inner_.make_rl()); }

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override {
    return inner_.loss(x, ws, team);
  }
  double rollout_with_grad(std::span<const double>, std::span<double>, Workspace&, ThreadTeam&) const override {
    throw std::logic_error("huge observation reach: no gradient");
  }

 private:
  testing::ReachEnv inner_;
};

TEST(PpoRuns, HugeObservationsAreClampedAndCounted) {
  // 30 episodes x 20 decisions: the position is 0 only at each reset (and wherever the actions
  // cancel exactly), so nearly every one of the 600 observations after a step is clamped
  HugeObservationReach huge;
  nlohmann::json d;
  const double best = best_of(huge, 30, "ppo", 5, &d);
  std::printf("huge observations: %lld components clamped in 30 episodes, best loss %.4g\n",
              static_cast<long long>(d["observations_sanitized"].get<std::int64_t>()), best);
  EXPECT_GT(d["observations_sanitized"].get<std::int64_t>(), 500);
  EXPECT_LE(d["observations_sanitized"].get<std::int64_t>(), 600);
  EXPECT_TRUE(std::isfinite(best));
  for (const double s : d["log_std"].get<std::vector<double>>()) EXPECT_TRUE(std::isfinite(s));
  // the plain reach env's observations are left as they are
  nlohmann::json plain;
  best_of(testing::ReachEnv(), 30, "ppo", 5, &plain);
  EXPECT_EQ(plain["observations_sanitized"].get<std::int64_t>(), 0);
}

TEST(PpoRuns, ExactBudgetAndIdenticalReruns) {
  const auto env = make_env("cartpole1");
  nlohmann::json d1, d2;
  std::vector<double> l1, l2;
  const double b1 = best_of(*env, 25, "ppo", 3, &d1, &l1);
  const double b2 = best_of(*env, 25, "ppo", 3, &d2, &l2);
  ASSERT_EQ(l1.size(), 25u);
  EXPECT_EQ(b1, b2);
  for (std::size_t i = 0; i < l1.size(); ++i) EXPECT_EQ(l1[i], l2[i]) << i;  // NaN-free here
  EXPECT_EQ(d1, d2);
  EXPECT_EQ(d1["episodes"], 25);
  EXPECT_EQ(d1["updates"], 1);  // 25 x 100 decisions: one rollout of 2,048 trained on
  // another seed, other episodes
  std::vector<double> l3;
  best_of(*env, 25, "ppo", 4, nullptr, &l3);
  EXPECT_NE(l1, l3);
}

TEST(RlHarness, PpoAndSacGiveTheSameResultsForAnyJobsAndPairOnlyWithRlEnvs) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("dsb_ppo_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string csv[2];
  for (int jobs : {1, 2}) {
    const std::string db = (dir / ("j" + std::to_string(jobs) + ".sqlite")).string();
    auto r = testing::run_harness(dir,
                                  "--env cartpole1,flip --optimizer ppo --seeds 2 --budget 12 --quiet --jobs " +
                                      std::to_string(jobs) + " --db " + db);
    ASSERT_EQ(r.code, 0) << r.err;
    // sac: 2 cartpole1 episodes = 200 decisions, 100 gradient steps after the random ones
    r = testing::run_harness(
        dir,
        "--env cartpole1 --optimizer sac --seeds 2 --budget 2 --quiet --jobs " + std::to_string(jobs) + " --db " + db);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string out = (dir / ("j" + std::to_string(jobs) + ".csv")).string();
    ASSERT_EQ(testing::run_harness(dir, "export --db " + db + " --out " + out).code, 0);
    csv[jobs - 1] = testing::read_file(out);
  }
  EXPECT_EQ(csv[0], csv[1]);
  EXPECT_EQ(std::count(csv[0].begin(), csv[0].end(), '\n'), 1 + 2 * 2 * 12 + 2 * 2);  // header + every episode
  // --all pairs ppo only with RL envs; an explicit pair with a non-RL env is a usage error
  auto plan = testing::run_harness(dir, "plan --env sphere-10,cartpole1 --all --seeds 1");
  ASSERT_EQ(plan.code, 0) << plan.err;
  // sphere-10 x the 10 non-RL optimizers + cartpole1 x all 12 (ppo and sac)
  EXPECT_NE((plan.out + plan.err).find("22 runs"), std::string::npos) << plan.out << plan.err;
  auto bad = testing::run_harness(
      dir, "--env sphere-10 --optimizer ppo --seeds 1 --budget 2 --db " + (dir / "bad.sqlite").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("needs an RL view"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

TEST(PpoConfigTest, InvalidFieldsAreNamed) {
  const auto field_of = [](auto mutate) {
    PpoConfig c;
    mutate(c);
    return testing::validation_message(c);
  };
  EXPECT_NE(field_of([](PpoConfig& c) { c.batch_size = 4096; }).find("batch_size"), std::string::npos);
  EXPECT_NE(field_of([](PpoConfig& c) { c.gamma = 1.5; }).find("gamma"), std::string::npos);
  EXPECT_NE(field_of([](PpoConfig& c) { c.hidden = {}; }).find("hidden"), std::string::npos);
  EXPECT_NE(field_of([](PpoConfig& c) { c.learning_rate = 0.0; }).find("learning_rate"), std::string::npos);
  EXPECT_EQ(field_of([](PpoConfig&) {}), "valid");
  // a gradient-free optimizer that needs an RL view: refused on an env without one, as sac is
  // (rl_core.hpp), before any episode
  const auto sphere = make_env("sphere-10");
  BudgetedObjective f(*sphere, 3);
  Rng rng(1);
  EXPECT_THROW(make_ppo()->minimize(f, rng), UsageError);
  EXPECT_EQ(f.used(), 0);
  EXPECT_TRUE(optimizer_entry("ppo").needs_rl);
}

}  // namespace
}  // namespace dsb
