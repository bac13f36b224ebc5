// The external optimizer protocol's cost per episode (docs/ext-protocol.md): a Python echo
// optimizer (tests/ext/test_optimizer.py echo BATCH, standard library json, through
// examples/ext/dsb_protocol.py) asks one random point of a cheap env (sphere-D, nanoseconds per
// episode) BATCH times per ask, for whole runs of kShort and kLong episodes; the difference of the
// two runs over kLong - kShort episodes cancels the start (process, imports, hello, end, exit),
// and the budget wrapper's own cost per episode (the same episodes in-process) is subtracted,
// leaving the round trip and the JSON on both sides. Reported per episode and as a ratio to one
// cartpole3 forward rollout measured in the same run, at D = 10 and at cartpole3's D = 400.
#include <cstdio>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "harness/run/budget.hpp"
#include "optimizers/ext/ext_optimizer.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

constexpr std::int64_t kShort = 256, kLong = 2048;

std::string echo_command(int batch, bool binary) {
  return std::string("/usr/bin/python3 " DSB_SOURCE_DIR "/tests/ext/test_optimizer.py ") +
      (binary ? "echo-binary " : "echo ") + std::to_string(batch);
}

std::string sphere(int dim) { return "sphere-" + std::to_string(dim); }

void BM_Cartpole3Forward(benchmark::State& state) {
  const auto env = dsb::make_env("cartpole3");
  const std::vector<double> x(env->dim(), 0.1);
  const auto ws = env->make_workspace();
  for (auto _ : state) benchmark::DoNotOptimize(env->loss(x, *ws, dsb::serial_team()));
}
BENCHMARK(BM_Cartpole3Forward)->Unit(benchmark::kMicrosecond);

// one whole run of an echo optimizer: args dim, batch, episodes, binary (0: JSON text, 1: base64)
void BM_ExtEchoRun(benchmark::State& state) {
  const int dim = static_cast<int>(state.range(0)), batch = static_cast<int>(state.range(1));
  const std::int64_t episodes = state.range(2);
  const auto env = dsb::make_env(sphere(dim));
  const auto spec = dsb::ext_probe({"echo", echo_command(batch, state.range(3) != 0), 60.0, "", ""});
  for (auto _ : state) {
    dsb::BudgetedObjective f(*env, episodes);
    auto opt = dsb::make_ext_optimizer(spec, env->name(), 1);
    dsb::Rng rng(1);
    try {
      opt->minimize(f, rng);
    } catch (const dsb::BudgetExhausted&) {}
    if (f.used() != episodes) state.SkipWithError("the echo run did not use its budget");
  }
}
BENCHMARK(BM_ExtEchoRun)
    ->ArgsProduct({{10, 400}, {1, 16, 64}, {kShort, kLong}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// the same episodes without the protocol: batches through the budget wrapper in-process
void BM_InProcessRun(benchmark::State& state) {
  const int dim = static_cast<int>(state.range(0)), batch = static_cast<int>(state.range(1));
  const auto env = dsb::make_env(sphere(dim));
  const std::vector<double> xs(static_cast<std::size_t>(dim * batch), 0.0);
  std::vector<double> out(static_cast<std::size_t>(batch));
  for (auto _ : state) {
    dsb::BudgetedObjective f(*env, kLong);
    while (f.remaining() >= batch) f.values(xs, out);
  }
}
BENCHMARK(BM_InProcessRun)->ArgsProduct({{10, 400}, {1, 16, 64}})->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return dsb::perf::run_benchmarks(argc, argv, [&](const dsb::perf::TimingReporter& reporter) {
    const double rollout = reporter.seconds("BM_Cartpole3Forward");
    std::printf(
        "\nprotocol overhead per episode (same run; (%lld-episode run - %lld-episode run) / %lld, minus the "
        "in-process episode):\n",
        static_cast<long long>(kLong), static_cast<long long>(kShort), static_cast<long long>(kLong - kShort));
    for (const int binary : {0, 1}) {
      for (const int dim : {10, 400}) {
        for (const int batch : {1, 16, 64}) {
          const std::string args = std::to_string(dim) + "/" + std::to_string(batch);
          auto run = [&](std::int64_t episodes) {
            return reporter.seconds("BM_ExtEchoRun/" + args + "/" + std::to_string(episodes) + "/" +
                                    std::to_string(binary) + "/real_time");
          };
          const double long_run = run(kLong), short_run = run(kShort),
                       direct = reporter.seconds("BM_InProcessRun/" + args);
          if (long_run <= 0 || short_run <= 0 || direct <= 0) continue;
          const double per_episode =
              (long_run - short_run) / static_cast<double>(kLong - kShort) - direct / static_cast<double>(kLong);
          std::printf("  %-6s D = %3d, batch %2d: %8.2f us per episode", binary ? "base64" : "JSON", dim, batch,
                      per_episode * 1e6);
          if (rollout > 0)
            std::printf(" = %6.3f x a cartpole3 forward rollout (%.1f us)", per_episode / rollout, rollout * 1e6);
          std::printf("\n");
        }
      }
    }
  });
}
