// The eight PlasticineLab tasks (`plb-NAME`, full 50-env-step horizon) through the Env interface,
// as the harness runs them:
//   - forward and gradient episode per task, 1 and 2 threads, at a seeded point of [-1, 1]^dim;
//   - the gradient/forward ratio per task, against the MLS-MPM engine's own figures (bench_mpm),
//     with the reverse pass recomputing every env step from its checkpoint (the tape memory 0)
//     and with every substep's tape kept from the forward pass (no recomputation), 1 thread;
//   - peak resident memory of a process that builds the task and runs one gradient episode, in
//     both modes.
// Benchmarks named *Full* time one whole episode after an untimed one (which builds the model and
// sizes the buffers, as a run's first episode does); the smoke test (filter -Full) runs plb-pinch-h5.
// The table printed at the end is the per-task table of docs/performance.md.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/mpm/plb_tasks.hpp"
#include "envs/registry.hpp"
#include "tests/perf/child_peak_rss.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

using namespace dsb;

// a seeded point of the normalized box (the same for every run of the bench)
std::vector<double> point(int dim) {
  Rng rng(20261124);
  std::vector<double> x(dim);
  for (double& v : x) v = 0.5 * (2.0 * rng.uniform() - 1.0);
  return x;
}

void episodes(benchmark::State& state, const std::string& env_name, bool gradient, std::size_t tape = 0) {
  const auto env = make_env(env_name);
  ThreadTeam team(static_cast<int>(state.range(0)));
  const auto ws = env->make_workspace();
  ws->tape_memory_bytes = tape;
  const auto x = point(env->dim());
  std::vector<double> g(x.size());
  // one untimed episode builds the model and sizes the buffers (the tapes: about 1 GB when all are
  // kept), as the first episode of a run does once for its other 999
  benchmark::DoNotOptimize(gradient ? env->loss_and_grad(x, g, *ws, team) : env->loss(x, *ws, team));
  for (auto _ : state)
    benchmark::DoNotOptimize(gradient ? env->loss_and_grad(x, g, *ws, team) : env->loss(x, *ws, team));
}

// peak RSS (MB) of a child process that builds the env and runs one gradient episode
double child_peak_rss_mb(const std::string& env_name, std::size_t tape = 0) {
  return perf::gradient_episode_peak_rss_mb(
      env_name, [](int dim) { return point(dim); }, tape);
}

std::string full_name(const char* what, const std::string& task, int threads) {
  return std::string("BM_Plb") + what + "Full/" + task + "/" + std::to_string(threads) + "/iterations:1/real_time";
}

}  // namespace

int main(int argc, char** argv) {
  bool full = true;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]).find("-Full") != std::string::npos) full = false;
  for (const auto& task : mpm::plb_tasks()) {
    const std::string env = "plb-" + task.name;
    for (const bool gradient : {false, true})
      benchmark::RegisterBenchmark(
          (std::string("BM_Plb") + (gradient ? "Gradient" : "Forward") + "Full/" + task.name).c_str(),
          [env, gradient](benchmark::State& s) { episodes(s, env, gradient); })
          ->Arg(1)
          ->Arg(2)
          ->Iterations(1)
          ->Unit(benchmark::kSecond)
          ->UseRealTime();
    benchmark::RegisterBenchmark((std::string("BM_PlbGradientTapedFull/") + task.name).c_str(),
                                 [env](benchmark::State& s) { episodes(s, env, true, mpm::kTapeEverything); })
        ->Arg(1)
        ->Iterations(1)
        ->Unit(benchmark::kSecond)
        ->UseRealTime();
  }
  benchmark::RegisterBenchmark("BM_PlbForwardH5/pinch", [](benchmark::State& s) { episodes(s, "plb-pinch-h5", false); })
      ->Arg(1)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark("BM_PlbGradientH5/pinch", [](benchmark::State& s) { episodes(s, "plb-pinch-h5", true); })
      ->Arg(1)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();

  std::vector<double> rss, rss_taped;
  if (full)
    for (const auto& task : mpm::plb_tasks()) {
      rss.push_back(child_peak_rss_mb("plb-" + task.name));
      rss_taped.push_back(child_peak_rss_mb("plb-" + task.name, mpm::kTapeEverything));
    }
  return perf::run_benchmarks(argc, argv, [&](const perf::TimingReporter& reporter) {
    if (reporter.seconds(full_name("Forward", mpm::plb_tasks().front().name, 1)) <= 0.0) return;
    std::printf(
        "\n| task | particles | dims | forward s (1 / 2 threads) | gradient s, recomputed (1 / 2 threads) | "
        "gradient s, taped (1 thread) | gradient / forward, recomputed / taped | peak MB, recomputed / taped "
        "|\n|---|---|---|---|---|---|---|---|\n");
    for (std::size_t i = 0; i < mpm::plb_tasks().size(); ++i) {
      const auto& task = mpm::plb_tasks()[i];
      const auto env = make_env("plb-" + task.name);
      int particles = 0;
      for (const auto& shape : task.shapes) particles += shape.particles;
      const double f1 = reporter.seconds(full_name("Forward", task.name, 1));
      const double f2 = reporter.seconds(full_name("Forward", task.name, 2));
      const double g1 = reporter.seconds(full_name("Gradient", task.name, 1));
      const double g2 = reporter.seconds(full_name("Gradient", task.name, 2));
      const double gt = reporter.seconds(full_name("GradientTaped", task.name, 1));
      const auto mb = [](const std::vector<double>& v, std::size_t k) {
        return k < v.size() ? std::to_string(static_cast<int>(std::lround(v[k]))) : std::string("-");
      };
      std::printf("| plb-%s | %d | %d | %.2f / %.2f | %.2f / %.2f | %.2f | %.2fx / %.2fx | %s / %s |\n",
                  task.name.c_str(), particles, env->dim(), f1, f2, g1, g2, gt, f1 > 0.0 ? g1 / f1 : 0.0,
                  f1 > 0.0 ? gt / f1 : 0.0, mb(rss, i).c_str(), mb(rss_taped, i).c_str());
    }
  });
}
