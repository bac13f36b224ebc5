// The seven cloth tasks (six `swing-*` and `flip`) through the Env interface, on one core:
//   - forward and gradient episode per task at a seeded point of [-1, 1]^dim, and the
//     gradient/forward ratio (goal <= 3x);
//   - the peer: a central-difference gradient of the same task (2 dim forward episodes),
//     measured in the same run, and its time over the adjoint's;
//   - 1,000 gradient episodes at 1,000 seeded points (what gd spends on a 1,000-episode budget;
//     goal < 60 s per task), and the peak resident memory of a process that runs one.
// Benchmarks named *Full run the 1,000-episode loops; the smoke test (filter -Full) runs the rest
// briefly. The table printed at the end is the cloth table of docs/performance.md.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "tests/perf/child_peak_rss.hpp"
#include "tests/perf/timing_reporter.hpp"

namespace {

using namespace dsb;

const std::vector<std::string>& tasks() {
  static const std::vector<std::string> names = {"swing-stiffness-single",
                                                 "swing-stiffness-corner",
                                                 "swing-stiffness-mesh",
                                                 "swing-velocity-single",
                                                 "swing-velocity-corner",
                                                 "swing-velocity-mesh",
                                                 "flip"};
  return names;
}

// seeded points of the normalized box, half its width (the same for every run of the bench)
std::vector<double> point(int dim, Rng& rng) {
  std::vector<double> x(dim);
  for (double& v : x) v = 0.5 * (2.0 * rng.uniform() - 1.0);
  return x;
}
std::vector<double> point(int dim) {
  Rng rng(20261124);
  return point(dim, rng);
}

enum class Kind { forward, gradient, central_difference };

void episodes(benchmark::State& state, const std::string& env_name, Kind kind) {
  const auto env = make_env(env_name);
  ThreadTeam team(1);
  const auto ws = env->make_workspace();
  auto x = point(env->dim());
  std::vector<double> g(x.size());
  for (auto _ : state) {
    switch (kind) {
      case Kind::forward: benchmark::DoNotOptimize(env->loss(x, *ws, team)); break;
      case Kind::gradient: benchmark::DoNotOptimize(env->loss_and_grad(x, g, *ws, team)); break;
      case Kind::central_difference:
        // (L(x + h e_i) - L(x - h e_i)) / 2h for every i
        for (std::size_t i = 0; i < x.size(); ++i) {
          const double xi = x[i], h = 1e-6;
          x[i] = xi + h;
          const double up = env->loss(x, *ws, team);
          x[i] = xi - h;
          const double down = env->loss(x, *ws, team);
          x[i] = xi;
          g[i] = (up - down) / (2.0 * h);
        }
        benchmark::DoNotOptimize(g.data());
        break;
    }
  }
}

// 1,000 gradient episodes at 1,000 seeded points
void thousand_gradients(benchmark::State& state, const std::string& env_name) {
  const auto env = make_env(env_name);
  ThreadTeam team(1);
  const auto ws = env->make_workspace();
  std::vector<double> g(env->dim());
  for (auto _ : state) {
    Rng rng(7);
    double sum = 0.0;
    for (int e = 0; e < 1000; ++e) sum += env->loss_and_grad(point(env->dim(), rng), g, *ws, team);
    benchmark::DoNotOptimize(sum);
  }
}

// peak RSS (MB) of a child process that builds the env and runs one gradient episode
double child_peak_rss_mb(const std::string& env_name) {
  return perf::gradient_episode_peak_rss_mb(env_name, [](int dim) { return point(dim); });
}

const char* kind_name(Kind k) {
  return k == Kind::forward ? "Forward" : k == Kind::gradient ? "Gradient" : "CentralDifference";
}

}  // namespace

int main(int argc, char** argv) {
  bool full = true;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]).find("-Full") != std::string::npos) full = false;
  for (const auto& task : tasks()) {
    for (const Kind kind : {Kind::forward, Kind::gradient, Kind::central_difference})
      benchmark::RegisterBenchmark((std::string("BM_Cloth") + kind_name(kind) + "/" + task).c_str(),
                                   [task, kind](benchmark::State& s) { episodes(s, task, kind); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    benchmark::RegisterBenchmark(("BM_Cloth1000GradientsFull/" + task).c_str(),
                                 [task](benchmark::State& s) { thousand_gradients(s, task); })
        ->Iterations(1)
        ->Unit(benchmark::kSecond)
        ->UseRealTime();
  }
  std::vector<double> rss;
  if (full)
    for (const auto& task : tasks()) rss.push_back(child_peak_rss_mb(task));
  return perf::run_benchmarks(argc, argv, [&](const perf::TimingReporter& reporter) {
    std::printf(
        "\n| task | dims | forward ms | gradient ms | gradient / forward | central differences ms "
        "(peer) | peer / gradient | 1,000 gradients s | peak MB |\n|---|---|---|---|---|---|---|---|---|\n");
    for (std::size_t i = 0; i < tasks().size(); ++i) {
      const std::string& task = tasks()[i];
      const double f = reporter.seconds("BM_ClothForward/" + task + "/real_time");
      const double g = reporter.seconds("BM_ClothGradient/" + task + "/real_time");
      const double cd = reporter.seconds("BM_ClothCentralDifference/" + task + "/real_time");
      const double k = reporter.seconds("BM_Cloth1000GradientsFull/" + task + "/iterations:1/real_time");
      if (f <= 0.0 || g <= 0.0) continue;
      std::printf("| %s | %d | %.2f | %.2f | %.2fx | %.1f | %.1fx | %s | %s |\n", task.c_str(), make_env(task)->dim(),
                  1e3 * f, 1e3 * g, g / f, 1e3 * cd, cd > 0.0 ? cd / g : 0.0,
                  k > 0.0 ? std::to_string(k).substr(0, 5).c_str() : "-",
                  i < rss.size() ? std::to_string(static_cast<int>(std::lround(rss[i]))).c_str() : "-");
    }
  });
}
