// cartpole3 rollout: forward only, forward + reverse-pass gradient, and the same gradient by
// central differences (2 x 400 rollouts), measured in one run and reported as ratios; plus a
// whole 1,000-episode `gd` run on one core through the budget wrapper. Rollouts reuse one
// workspace as the harness does; heap allocations per rollout are counted (operator new is
// replaced in this binary) and shown beside a rollout with a fresh workspace.
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "harness/run/runner.hpp"
#include "optimizers/registry.hpp"
#include "tests/perf/allocation_counter.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

using dsb::perf::AllocationCounter;

std::vector<double> point(const dsb::Env& env) {
  dsb::Rng rng(1);
  std::vector<double> x(env.dim());
  for (auto& xi : x) xi = 0.5 * rng.uniform(-1.0, 1.0);
  return x;
}

void BM_Cartpole3Forward(benchmark::State& state) {
  const auto env = dsb::make_env("cartpole3");
  const auto x = point(*env);
  const auto ws = env->make_workspace();
  const AllocationCounter allocations;
  for (auto _ : state) benchmark::DoNotOptimize(env->loss(x, *ws, dsb::serial_team()));
  allocations.report(state);
}
BENCHMARK(BM_Cartpole3Forward);

void BM_Cartpole3ForwardGradient(benchmark::State& state) {
  const auto env = dsb::make_env("cartpole3");
  const auto x = point(*env);
  std::vector<double> g(env->dim());
  const auto ws = env->make_workspace();
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(env->loss_and_grad(x, g, *ws, dsb::serial_team()));
    benchmark::ClobberMemory();
  }
  allocations.report(state);
}
BENCHMARK(BM_Cartpole3ForwardGradient);

// the same with a new workspace per rollout (what the pre-workspace env allocated: the state and
// step-cache histories)
void BM_Cartpole3ForwardGradientFreshWorkspace(benchmark::State& state) {
  const auto env = dsb::make_env("cartpole3");
  const auto x = point(*env);
  std::vector<double> g(env->dim());
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(env->loss_and_grad(x, g));
    benchmark::ClobberMemory();
  }
  allocations.report(state);
}
BENCHMARK(BM_Cartpole3ForwardGradientFreshWorkspace);

void BM_Cartpole3CentralDifferences(benchmark::State& state) {
  const auto env = dsb::make_env("cartpole3");
  auto x = point(*env);
  std::vector<double> g(env->dim());
  for (auto _ : state) {
    for (int i = 0; i < env->dim(); ++i) {
      const double xi = x[i];
      x[i] = xi + 1e-6;
      const double fp = env->loss(x);
      x[i] = xi - 1e-6;
      const double fm = env->loss(x);
      x[i] = xi;
      g[i] = (fp - fm) / 2e-6;
    }
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Cartpole3CentralDifferences)->Unit(benchmark::kMillisecond);

void BM_GdRun1000EpisodesCartpole3(benchmark::State& state) {
  const auto env = dsb::make_env("cartpole3");
  const AllocationCounter allocations;
  for (auto _ : state) {
    auto gd = dsb::make_optimizer("gd");
    const auto r = dsb::execute_run({"cartpole3", "gd", 0, 1000, 1}, *env, *gd);
    benchmark::DoNotOptimize(r.best_loss);
  }
  allocations.report(state);  // per 1,000-episode run here
}
BENCHMARK(BM_GdRun1000EpisodesCartpole3)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return dsb::perf::run_benchmarks(argc, argv, [&](const dsb::perf::TimingReporter& reporter) {
    const double fwd = reporter.seconds("BM_Cartpole3Forward"), grad = reporter.seconds("BM_Cartpole3ForwardGradient"),
                 fresh = reporter.seconds("BM_Cartpole3ForwardGradientFreshWorkspace"),
                 fd = reporter.seconds("BM_Cartpole3CentralDifferences"),
                 gd = reporter.seconds("BM_GdRun1000EpisodesCartpole3");
    if (fwd > 0 && grad > 0 && fd > 0) {
      std::printf("\nratios (same run):\n");
      std::printf("  forward+gradient / forward          = %6.2f   (target <= 3)\n", grad / fwd);
      std::printf("  central differences / reverse pass   = %6.0f   (target >= 100)\n", fd / grad);
      if (fresh > 0) std::printf("  fresh workspace / reused workspace   = %6.2f\n", fresh / grad);
    }
    if (gd > 0) std::printf("  1000-episode gd run on cartpole3     = %6.3f s (target < 2 s)\n", gd);
  });
}
