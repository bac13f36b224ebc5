// Rigid envs against the reference engines, measured in one run and reported as ratios:
//   - one cartpole3 step (as a 100-step episode per iteration, the same controls everywhere): our
//     cartpole_step, MuJoCo's plain mj_step on the same model (joint torques applied), MuJoCo
//     with our velocity control (mj_step1, the cart force from the mass matrix, mj_step2: what the
//     cross-check runs) and Bullet's btMultiBody with its motor;
//   - the gradient of a whole bounce episode (960 steps): our reverse pass against MuJoCo central
//     differences over the same 3 parameters (6 MuJoCo rollouts).
// Without an engine its benchmarks report an error and its ratios are left out.
#include <cstdio>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/rng.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_env.hpp"
#include "reference/bullet_adapter.hpp"
#include "reference/mujoco_adapter.hpp"
#include "tests/perf/timing_reporter.hpp"

#if DSB_HAVE_MUJOCO
#include <mujoco/mujoco.h>
#endif

namespace {

using namespace dsb;
using namespace dsb::reference;

constexpr int kSteps = 100;  // cartpole3 episode

// physical controls of a seeded cartpole3 episode: normalized parameters uniform in [-0.5, 0.5]
// through the env's parameter map, per step u then 3 torques
std::vector<double> cartpole_controls(const CartpoleConfig& cfg) {
  const CartpoleEnv env("cartpole3", cfg);
  Rng rng(3);
  std::vector<double> x(env.dim());
  for (auto& xi : x) xi = rng.uniform(-0.5, 0.5);
  std::vector<double> c;
  for (int t = 0; t < cfg.steps; ++t) {
    const CartpoleControls step = env.controls(x, t);
    c.push_back(step.u);
    c.insert(c.end(), step.tau, step.tau + cfg.links);
  }
  return c;
}

void BM_Cartpole3StepOurs(benchmark::State& state) {
  const CartpoleConfig cfg = CartpoleConfig::three_links();
  const CartpoleModel model = CartpoleModel::build(cfg);
  const auto c = cartpole_controls(cfg);
  for (auto _ : state) {
    CartpoleState s = cartpole_initial_state(model, cfg);
    for (int t = 0; t < kSteps; ++t) cartpole_step(model, s, c[4 * t], &c[4 * t + 1]);
    benchmark::DoNotOptimize(s.phi.data());
  }
  state.SetItemsProcessed(state.iterations() * kSteps);
}
BENCHMARK(BM_Cartpole3StepOurs);

void BM_Cartpole3StepMujoco(benchmark::State& state) {
#if DSB_HAVE_MUJOCO
  // the same compiled model; plain mj_step with the joint torques as applied forces
  const CartpoleConfig cfg = CartpoleConfig::three_links();
  const auto c = cartpole_controls(cfg);
  MujocoCartpole cp(cfg);
  const mjModel* m = cp.sim().model();
  mjData* d = cp.sim().data();
  for (auto _ : state) {
    mj_resetData(m, d);
    for (int t = 0; t < kSteps; ++t) {
      for (int j = 0; j < 3; ++j) d->qfrc_applied[1 + j] = c[4 * t + 1 + j];
      mj_step(m, d);
    }
    benchmark::DoNotOptimize(d->qpos);
  }
  state.SetItemsProcessed(state.iterations() * kSteps);
#else
  state.SkipWithError("built without MuJoCo");
#endif
}
BENCHMARK(BM_Cartpole3StepMujoco);

// kSteps cartpole3 steps of a reference engine's adapter (MujocoCartpole, BulletCartpole), reset
// each iteration
template <class Engine>
void cartpole3_adapter_steps(benchmark::State& state) {
  const CartpoleConfig cfg = CartpoleConfig::three_links();
  const auto c = cartpole_controls(cfg);
  Engine cp(cfg);
  for (auto _ : state) {
    cp.reset();
    for (int t = 0; t < kSteps; ++t) cp.step(c[4 * t], &c[4 * t + 1]);
    benchmark::DoNotOptimize(cp.state().x);
  }
  state.SetItemsProcessed(state.iterations() * kSteps);
}

void BM_Cartpole3StepMujocoVelocityControl(benchmark::State& state) {
  if (!mujoco_available()) return state.SkipWithError("built without MuJoCo");
  cartpole3_adapter_steps<MujocoCartpole>(state);
}
BENCHMARK(BM_Cartpole3StepMujocoVelocityControl);

void BM_Cartpole3StepBullet(benchmark::State& state) {
  if (!bullet_available()) return state.SkipWithError("built without Bullet");
  cartpole3_adapter_steps<BulletCartpole>(state);
}
BENCHMARK(BM_Cartpole3StepBullet);

const std::vector<double> kThrow = {0.3, -0.4, 0.2};  // a throw that bounces on ground and wall

void BM_BounceGradientOurs(benchmark::State& state) {
  const BounceEnv env;
  std::vector<double> g(3);
  for (auto _ : state) {
    benchmark::DoNotOptimize(env.loss_and_grad(kThrow, g));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_BounceGradientOurs)->Unit(benchmark::kMicrosecond);

void BM_BounceRolloutMujoco(benchmark::State& state) {
  if (!mujoco_available()) return state.SkipWithError("built without MuJoCo");
  const BounceEnv env;
  MujocoBounce mj(env.bounce_config());
  for (auto _ : state) benchmark::DoNotOptimize(env.final_loss(mj.final_state(env.initial_velocity(kThrow))));
}
BENCHMARK(BM_BounceRolloutMujoco)->Unit(benchmark::kMicrosecond);

void BM_BounceCentralDifferencesMujoco(benchmark::State& state) {
  if (!mujoco_available()) return state.SkipWithError("built without MuJoCo");
  // dLoss/dx by central differences in the same normalized parameters: 6 MuJoCo rollouts
  const BounceEnv env;
  MujocoBounce mj(env.bounce_config());
  std::vector<double> x = kThrow, g(3);
  const double h = 1e-6;
  auto loss = [&] { return env.final_loss(mj.final_state(env.initial_velocity(x))); };
  for (auto _ : state) {
    for (int i = 0; i < 3; ++i) {
      const double xi = x[i];
      x[i] = xi + h;
      const double fp = loss();
      x[i] = xi - h;
      const double fm = loss();
      x[i] = xi;
      g[i] = (fp - fm) / (2.0 * h);
    }
    benchmark::DoNotOptimize(g.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_BounceCentralDifferencesMujoco)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  return perf::run_benchmarks(argc, argv, [&](const perf::TimingReporter& reporter) {
    const double ours = reporter.seconds("BM_Cartpole3StepOurs"), mj = reporter.seconds("BM_Cartpole3StepMujoco"),
                 mj_vc = reporter.seconds("BM_Cartpole3StepMujocoVelocityControl"),
                 bt = reporter.seconds("BM_Cartpole3StepBullet"), grad = reporter.seconds("BM_BounceGradientOurs"),
                 fd = reporter.seconds("BM_BounceCentralDifferencesMujoco");
    std::printf("\nratios (same run):\n");
    if (ours > 0) {
      std::printf("  cartpole3 step, ours                          = %8.3f us\n", 1e6 * ours / kSteps);
      if (mj > 0)
        std::printf("  mj_step / our step                            = %8.2f   (target >= 1: ours not slower)\n",
                    mj / ours);
      if (mj_vc > 0) std::printf("  MuJoCo velocity-controlled step / our step    = %8.2f\n", mj_vc / ours);
      if (bt > 0) std::printf("  Bullet btMultiBody step / our step            = %8.2f\n", bt / ours);
    }
    if (grad > 0 && fd > 0)
      std::printf("  bounce gradient: MuJoCo central differences (6 rollouts) / our reverse pass = %6.2f\n", fd / grad);
  });
}
