// GP and acquisition costs at the sizes a 1,000-episode run reaches (n = 1,000 points, 10-D):
// one hyperparameter refit, one LCB minimization, one O(n^2) add_point against a fresh O(n^3)
// factorization (ratio printed), and whole runs: `bo` on a 10-D env and `boleap`'s overhead.
// The whole-run benchmarks are named Full* and are excluded from the CI smoke run.
#include <cstdio>

#include <benchmark/benchmark.h>

#include "envs/registry.hpp"
#include "harness/runner.hpp"
#include "optimizers/bo/acquisition.hpp"
#include "optimizers/bo/gp.hpp"
#include "optimizers/registry.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

constexpr int kDim = 10;

// n points of rastrigin-10 scaled to the unit box, as bo would hold them
void data(int n, Eigen::MatrixXd& X, Eigen::VectorXd& y) {
  dsb::Rng rng(1);
  const auto env = dsb::make_env("rastrigin-10");
  X.resize(n, kDim);
  y.resize(n);
  std::vector<double> x(kDim);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < kDim; ++j) {
      X(i, j) = rng.uniform();
      x[j] = 2.0 * X(i, j) - 1.0;
    }
    y[i] = env->loss(x);
  }
}

dsb::GaussianProcess fitted_gp(int n) {
  Eigen::MatrixXd X;
  Eigen::VectorXd y;
  data(n, X, y);
  dsb::GaussianProcess gp(kDim, dsb::GpConfig{});
  gp.set_data(X, y);
  dsb::Rng rng(2);
  gp.fit(rng);
  return gp;
}

void BM_GpRefit(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Eigen::MatrixXd X;
  Eigen::VectorXd y;
  data(n, X, y);
  for (auto _ : state) {
    dsb::GaussianProcess gp(kDim, dsb::GpConfig{});
    gp.set_data(X, y);
    dsb::Rng rng(2);
    gp.fit(rng);
    benchmark::DoNotOptimize(gp.hyperparameters().noise);
  }
}
BENCHMARK(BM_GpRefit)->Arg(100)->Arg(1000)->Unit(benchmark::kSecond)->Iterations(1);

void BM_LcbMinimization(benchmark::State& state) {
  const auto gp = fitted_gp(static_cast<int>(state.range(0)));
  dsb::Rng rng(3);
  for (auto _ : state) benchmark::DoNotOptimize(dsb::minimize_lcb(gp, dsb::LcbConfig{}, rng));
}
BENCHMARK(BM_LcbMinimization)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_GpAddPoint(benchmark::State& state) {
  auto gp = fitted_gp(static_cast<int>(state.range(0)));
  const auto base = gp;
  dsb::Rng rng(4);
  for (auto _ : state) {
    state.PauseTiming();
    gp = base;
    Eigen::VectorXd u(kDim);
    for (int j = 0; j < kDim; ++j) u[j] = rng.uniform();
    state.ResumeTiming();
    gp.add_point(u, 1.0);
  }
}
BENCHMARK(BM_GpAddPoint)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_GpRefactorization(benchmark::State& state) {
  auto gp = fitted_gp(static_cast<int>(state.range(0)));
  const auto h = gp.hyperparameters();
  for (auto _ : state) gp.set_hyperparameters(h);  // rebuilds K and factors it: O(n^3)
}
BENCHMARK(BM_GpRefactorization)->Arg(1000)->Unit(benchmark::kMillisecond);

void run_full(benchmark::State& state, const std::string& env_name, const std::string& opt_name) {
  const auto env = dsb::make_env(env_name);
  for (auto _ : state) {
    auto opt = dsb::make_optimizer(opt_name);
    const auto r = dsb::execute_run({env_name, opt_name, 0, 1000, 1}, *env, *opt);
    benchmark::DoNotOptimize(r.best_loss);
  }
}
void BM_FullBoRun1000Rastrigin10(benchmark::State& s) { run_full(s, "rastrigin-10", "bo"); }
void BM_FullBoleapRun1000Rastrigin10(benchmark::State& s) { run_full(s, "rastrigin-10", "boleap"); }
BENCHMARK(BM_FullBoRun1000Rastrigin10)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_FullBoleapRun1000Rastrigin10)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  return dsb::perf::run_benchmarks(argc, argv, [&](const dsb::perf::TimingReporter& rep) {
    const double add = rep.seconds("BM_GpAddPoint/1000"), full = rep.seconds("BM_GpRefactorization/1000");
    if (add > 0 && full > 0)
      std::printf("\nratio (same run): full factorization / O(n^2) add_point at n = 1000 = %.0f\n", full / add);
    for (const char* name : {"BM_FullBoRun1000Rastrigin10/iterations:1", "BM_FullBoleapRun1000Rastrigin10/iterations:1"})
      if (rep.seconds(name) > 0) std::printf("%s: %.1f s (targets: bo < 300 s, boleap < 60 s)\n", name, rep.seconds(name));
  });
}
