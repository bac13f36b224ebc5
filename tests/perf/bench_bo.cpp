// GP and acquisition costs at the sizes a 1,000-episode run reaches (n = 1,000 points, 10-D):
// one hyperparameter refit, one LCB minimization, one O(n^2) add_point against a fresh O(n^3)
// factorization (ratio printed), and whole runs: `bo` on a 10-D env and `boleap`'s overhead.
// The GP's pairwise kernels at a 400-D run's size (n = 1,000 points, d = 400: cartpole3), each
// SIMD path against the scalar reference in the same run, and one likelihood evaluation with its
// gradient at that size.
// The whole-run benchmarks are named Full* and are excluded from the CI smoke run.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "envs/registry.hpp"
#include "harness/run/runner.hpp"
#include "optimizers/bo/acquisition.hpp"
#include "optimizers/bo/gp.hpp"
#include "optimizers/bo/gp_pairs.hpp"
#include "optimizers/registry.hpp"
#include "common/simd_path.hpp"
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

// n points in [0, 1]^d divided by lengthscales in [0.05, 20], in both layouts the kernels take:
// xs (d x n) and xt (n x d), column-major
constexpr int kPairsN = 1000, kPairsD = 400;
struct ScaledPoints {
  std::vector<double> xs, xt, c;
  ScaledPoints() : xs(kPairsN * kPairsD), xt(kPairsN * kPairsD), c(kPairsN * kPairsN) {
    dsb::Rng rng(5);
    std::vector<double> l(kPairsD);
    for (double& v : l) v = 0.05 * std::pow(400.0, rng.uniform());
    for (int a = 0; a < kPairsN; ++a)
      for (int i = 0; i < kPairsD; ++i) xs[a * kPairsD + i] = xt[i * kPairsN + a] = rng.uniform() / l[i];
    for (double& v : c) v = rng.uniform() - 0.5;
  }
};
const ScaledPoints& scaled_points() {
  static const ScaledPoints p;
  return p;
}

// range(0): 0 scalar, 1 sse2, 2 avx (skipped where the CPU has no AVX)
bool pairs_path(benchmark::State& state, dsb::SimdPath* path) {
  *path = static_cast<dsb::SimdPath>(state.range(0));
  if (*path == dsb::SimdPath::avx && !dsb::cpu_supports(dsb::SimdPath::avx)) {
    state.SkipWithError("no AVX on this CPU");
    return false;
  }
  return true;
}

void BM_GpPairDistances(benchmark::State& state) {
  dsb::SimdPath path;
  if (!pairs_path(state, &path)) return;
  const auto& p = scaled_points();
  std::vector<double> R(kPairsN * kPairsN);
  for (auto _ : state) {
    dsb::gp_pairs::squared_distances(p.xt.data(), kPairsN, kPairsD, R.data(), path);
    benchmark::DoNotOptimize(R.data());
  }
}
BENCHMARK(BM_GpPairDistances)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_GpArdGradient(benchmark::State& state) {
  dsb::SimdPath path;
  if (!pairs_path(state, &path)) return;
  const auto& p = scaled_points();
  std::vector<double> gl(kPairsD, 0.0);
  for (auto _ : state) {
    dsb::gp_pairs::ard_gradient(p.xs.data(), kPairsN, kPairsD, p.c.data(), gl.data(), path);
    benchmark::DoNotOptimize(gl.data());
  }
}
BENCHMARK(BM_GpArdGradient)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// one likelihood evaluation with its gradient (what each L-BFGS step of a fit costs) at n = 1,000
// in 400-D, the default path
void BM_GpLikelihoodGradient400D(benchmark::State& state) {
  Eigen::MatrixXd X(kPairsN, kPairsD);
  Eigen::VectorXd y(kPairsN);
  dsb::Rng rng(6);
  for (int a = 0; a < kPairsN; ++a) {
    double r2 = 0.0;
    for (int i = 0; i < kPairsD; ++i) {
      X(a, i) = rng.uniform();
      r2 += (X(a, i) - 0.5) * (X(a, i) - 0.5);
    }
    y[a] = r2 + 0.1 * rng.uniform();
  }
  dsb::GaussianProcess gp(kPairsD, dsb::GpConfig{});
  gp.set_data(X, y);
  const Eigen::VectorXd theta = gp.theta_of(gp.hyperparameters());
  Eigen::VectorXd g;
  for (auto _ : state) benchmark::DoNotOptimize(gp.fit_objective(theta, &g));
}
BENCHMARK(BM_GpLikelihoodGradient400D)->Unit(benchmark::kMillisecond);

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
    for (const char* kernel : {"BM_GpPairDistances", "BM_GpArdGradient"}) {
      const double scalar = rep.seconds(std::string(kernel) + "/0");
      const double sse2 = rep.seconds(std::string(kernel) + "/1"), avx = rep.seconds(std::string(kernel) + "/2");
      if (scalar > 0 && sse2 > 0)
        std::printf("ratio (same run): %s at n = 1000, d = 400, scalar / sse2 = %.2f%s\n", kernel, scalar / sse2,
                    avx > 0 ? (", scalar / avx = " + std::to_string(scalar / avx)).c_str() : "");
    }
    for (const char* name :
         {"BM_FullBoRun1000Rastrigin10/iterations:1", "BM_FullBoleapRun1000Rastrigin10/iterations:1"})
      if (rep.seconds(name) > 0)
        std::printf("%s: %.1f s (targets: bo < 300 s, boleap < 60 s)\n", name, rep.seconds(name));
  });
}
