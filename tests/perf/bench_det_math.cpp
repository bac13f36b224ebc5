// Cost of the deterministic elementary functions (common/det_math, SLEEF's pure-C scalar code)
// against glibc's libm (which uses FMA/AVX2 variants where the CPU has them), per call, over 4096
// independent arguments in a typical range; reported as ratios det / glibc measured in one run.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/det_math.hpp"
#include "common/rng.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

constexpr int kArgs = 4096;

std::vector<double> arguments(double lo, double hi) {
  dsb::Rng rng(3);
  std::vector<double> x(kArgs);
  for (double& v : x) v = rng.uniform(lo, hi);
  return x;
}

template <typename F>
void run_unary(benchmark::State& state, F f, double lo, double hi) {
  const auto x = arguments(lo, hi);
  for (auto _ : state) {
    double sum = 0.0;
    for (double v : x) sum += f(v);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * kArgs);
}

// one benchmark per (function, implementation); the range is where the code calls it
#define DSB_BENCH_UNARY(fn, lo, hi)                          \
  void BM_##fn##_glibc(benchmark::State& s) {                \
    run_unary(                                               \
        s, [](double v) { return ::fn(v); }, lo, hi);        \
  }                                                          \
  void BM_##fn##_det(benchmark::State& s) {                  \
    run_unary(                                               \
        s, [](double v) { return dsb::dm::fn(v); }, lo, hi); \
  }                                                          \
  BENCHMARK(BM_##fn##_glibc);                                \
  BENCHMARK(BM_##fn##_det);

DSB_BENCH_UNARY(exp, -20.0, 5.0)
DSB_BENCH_UNARY(log, 1e-3, 1e3)
DSB_BENCH_UNARY(sin, -4.0, 4.0)
DSB_BENCH_UNARY(cos, -4.0, 4.0)
DSB_BENCH_UNARY(tanh, -5.0, 5.0)

void BM_pow_glibc(benchmark::State& s) {
  run_unary(
      s, [](double v) { return ::pow(v, 0.37); }, 1e-3, 1e3);
}
void BM_pow_det(benchmark::State& s) {
  run_unary(
      s, [](double v) { return dsb::dm::pow(v, 0.37); }, 1e-3, 1e3);
}
BENCHMARK(BM_pow_glibc);
BENCHMARK(BM_pow_det);

}  // namespace

int main(int argc, char** argv) {
  return dsb::perf::run_benchmarks(argc, argv, [&](const dsb::perf::TimingReporter& reporter) {
    std::printf("\nper call, det / glibc (same run):\n");
    for (const char* fn : {"exp", "log", "sin", "cos", "tanh", "pow"}) {
      const double g = reporter.seconds(std::string("BM_") + fn + "_glibc") / kArgs,
                   d = reporter.seconds(std::string("BM_") + fn + "_det") / kArgs;
      if (g > 0 && d > 0) std::printf("  %-5s %6.1f ns vs %6.1f ns  = %5.2f x\n", fn, 1e9 * d, 1e9 * g, d / g);
    }
  });
}
