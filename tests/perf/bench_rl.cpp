// The RL learners' cost per decision against the env step they drive (cartpole3: the cheapest
// simulator step we have, 0.13 us), measured in the same run:
//   - the env: one RlEnv::step of cartpole3 (the peer);
//   - ppo, where the time goes: acting (policy and value forward for one observation, sampling,
//     log-probability) and one minibatch update (loss and gradient on 64 decisions, gradient clip,
//     Adam), amortised per decision over a rollout (n_epochs x n_steps / batch_size minibatches
//     per n_steps decisions);
//   - ppo end to end: a run of 21 cartpole3 episodes (2,100 decisions, one update) through the
//     budgeted objective, minus 2,100 env steps;
//   - sac end to end: a run of 3 cartpole3 episodes (300 decisions: 100 random ones, then one
//     gradient step of batch 256 per decision), minus its env steps, per gradient step.
// The table printed at the end is docs/performance.md's.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "harness/run/budget.hpp"
#include "optimizers/rl/gaussian.hpp"
#include "optimizers/rl/network_adam.hpp"
#include "optimizers/rl/ppo.hpp"
#include "optimizers/rl/sac.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

using namespace dsb;

constexpr int kObs = 9, kAct = 4;  // cartpole3's RL view

void BM_Cartpole3RlStep(benchmark::State& state) {
  const auto env = make_env("cartpole3");
  auto rl = env->make_rl();
  std::vector<double> a(rl->action_dim(), 0.1);
  rl->reset();
  for (auto _ : state) {
    if (rl->done()) rl->reset();
    rl->step(a);
  }
}
BENCHMARK(BM_Cartpole3RlStep);

// PPO's two networks at the cartpole3 sizes, initialised as a run does (SB3's orthogonal init)
PpoNetworks initialised_networks(const PpoConfig& cfg, Rng& rng) {
  PpoNetworks nets(kObs, kAct, cfg);
  nets.init(cfg, rng);
  return nets;
}

void BM_PpoAct(benchmark::State& state) {
  PpoConfig cfg;
  Rng rng(1);
  PpoNetworks nets = initialised_networks(cfg, rng);
  std::vector<double> obs(kObs, 0.1), a(kAct);
  for (auto _ : state) {
    const Eigen::Map<const Eigen::VectorXd> o(obs.data(), kObs);
    const Eigen::VectorXd mu = nets.policy.forward_one(o);
    benchmark::DoNotOptimize(nets.value.forward_one(o)(0));
    diag_gaussian_sample(std::span<const double>(mu.data(), kAct), nets.log_std, rng, a);
    benchmark::DoNotOptimize(diag_gaussian_log_prob(a, std::span<const double>(mu.data(), kAct), nets.log_std));
  }
}
BENCHMARK(BM_PpoAct);

void BM_PpoMinibatch(benchmark::State& state) {
  PpoConfig cfg;
  Rng rng(2);
  PpoNetworks nets = initialised_networks(cfg, rng);
  const int B = cfg.batch_size;
  PpoBatch batch;
  batch.observations = Eigen::MatrixXd::Random(kObs, B);
  batch.actions = Eigen::MatrixXd::Random(kAct, B);
  batch.old_log_prob.assign(B, -4.0);
  batch.advantages.resize(B);
  batch.returns.resize(B);
  for (int i = 0; i < B; ++i) batch.advantages[i] = batch.returns[i] = rng.uniform(-1.0, 1.0);
  AdamConfig adam{cfg.learning_rate, 0.9, 0.999, cfg.adam_eps};
  const std::size_t np = nets.policy.param_count(), nv = nets.value.param_count();
  NetworkAdam a_pi(adam, np), a_v(adam, nv), a_ls(adam, kAct);
  std::vector<double> grad(nets.param_count());
  for (auto _ : state) {
    std::fill(grad.begin(), grad.end(), 0.0);
    benchmark::DoNotOptimize(ppo_loss(nets, batch, cfg, grad).loss);
    clip_grad_norm(grad, cfg.max_grad_norm);
    const std::span<double> g(grad);
    a_pi.step(nets.policy.params(), g.subspan(0, np));
    a_v.step(nets.value.params(), g.subspan(np, nv));
    a_ls.step(nets.log_std, g.subspan(np + nv));
  }
}
BENCHMARK(BM_PpoMinibatch);

// a whole run of `optimizer` on cartpole3 with `budget` episodes through the budgeted objective
void run_on_cartpole3(benchmark::State& state, std::unique_ptr<Optimizer> (*make)(), std::int64_t budget) {
  const auto env = make_env("cartpole3");
  for (auto _ : state) {
    BudgetedObjective f(*env, budget);
    auto opt = make();
    Rng rng(3);
    try {
      opt->minimize(f, rng);
    } catch (const BudgetExhausted&) {}
    benchmark::DoNotOptimize(f.best_loss());
  }
}
std::unique_ptr<Optimizer> default_ppo() { return make_ppo(); }
std::unique_ptr<Optimizer> default_sac() { return make_sac(); }
void BM_PpoRunCartpole3(benchmark::State& state) { run_on_cartpole3(state, default_ppo, 21); }
BENCHMARK(BM_PpoRunCartpole3)->Unit(benchmark::kMillisecond);
void BM_SacRunCartpole3(benchmark::State& state) { run_on_cartpole3(state, default_sac, 3); }
BENCHMARK(BM_SacRunCartpole3)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return perf::run_benchmarks(argc, argv, [&](const perf::TimingReporter& reporter) {
    const double env = reporter.seconds("BM_Cartpole3RlStep");
    const double act = reporter.seconds("BM_PpoAct");
    const double mb = reporter.seconds("BM_PpoMinibatch");
    const double run = reporter.seconds("BM_PpoRunCartpole3");
    if (env <= 0.0 || act <= 0.0 || mb <= 0.0) return;
    const PpoConfig cfg;
    const double minibatches = cfg.n_epochs * ((cfg.n_steps + cfg.batch_size - 1) / cfg.batch_size);
    const double update = mb * minibatches / cfg.n_steps;
    std::printf("\n| per decision on cartpole3 | us | x env step |\n|---|---|---|\n");
    std::printf("| env step (peer) | %.3f | 1 |\n", 1e6 * env);
    std::printf("| ppo acting (2 forward passes, sample, log-prob) | %.2f | %.0f |\n", 1e6 * act, act / env);
    std::printf(
        "| ppo update, amortised (%.0f minibatches of %d per %d decisions; one minibatch %.0f us) | %.2f | %.0f |\n",
        minibatches, cfg.batch_size, cfg.n_steps, 1e6 * mb, 1e6 * update, update / env);
    std::printf("| ppo learner in all | %.2f | %.0f |\n", 1e6 * (act + update), (act + update) / env);
    const double sac = reporter.seconds("BM_SacRunCartpole3");
    if (sac > 0.0) {
      const double per_step = (sac - 300 * env) / 200;
      std::printf(
          "| sac end to end: a 3-episode run (300 decisions, 200 gradient steps of batch 256) minus its env "
          "steps, per gradient step | %.0f | %.0f |\n",
          1e6 * per_step, per_step / env);
    }
    if (run > 0.0) {
      const double learner = (run - 2100 * env) / 2100;
      std::printf(
          "| ppo end to end: a 21-episode run (2,100 decisions, one update) minus its env steps | %.2f | %.0f |\n",
          1e6 * learner, learner / env);
    }
  });
}
