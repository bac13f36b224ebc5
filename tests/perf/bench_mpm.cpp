// The MLS-MPM engine on a PlasticineLab-sized model (10,000 von Mises particles, 64^3 grid,
// dt 1e-4, 19 substeps x 50 env steps = 950 substeps, a sphere pressing in with soft contact):
//   - forward episode, particle-substeps per second, 1 and 2 threads;
//   - gradient episode (forward + checkpointed reverse) against the forward, 1 and 2 threads, and with
//     every substep's tape kept from the forward pass (no recomputation), 1 thread;
//   - the phase breakdown of both (stress = F update + SVD + return mapping + stress);
//   - peak resident memory of a process that runs one gradient episode, against the full
//     history's size (950 states of every particle).
//   - heap allocations per `fluid` rollout with a reused workspace (fluid-h5, forward and gradient).
//   - the lanes path (envs/mpm/lane_path.hpp: the best the CPU has, or DSB_SIMD) against the
//     scalar path, measured in the same run (*Scalar* benchmarks force it), 1 thread; and within
//     one forward episode whose env steps alternate between the paths, and gradient episodes of
//     5 env steps taking turns (both paths under the same load: the machine is shared).
// Benchmarks named *Full* run the whole episode once; the smoke test (filter -Full) runs 1 env
// step. Ratios print at the end.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/registry.hpp"
#include "tests/perf/allocation_counter.hpp"
#include "tests/perf/timing_reporter.hpp"
#include "tests/support/mpm_models.hpp"

namespace {

using namespace dsb;
using namespace dsb::mpm;

constexpr int kParticles = 10000;
constexpr int kEnvSteps = 50;

// PlasticineLab's defaults (MpmConfig, Material): a 0.3 x 0.1 x 0.3 box of uniformly sampled
// particles (its RollingPin/Writer/Torus shape) and a sphere of radius 0.04 moving into it
const MpmModel& plb_sized_model() {
  static const MpmModel model = [] {
    MpmModel m;
    m.materials = {Material{}};
    Rng rng(0);
    for (int i = 0; i < kParticles; ++i) {
      Particle p;
      p.x = Vec3(0.35 + 0.3 * rng.uniform(), 0.05 + 0.1 * rng.uniform(), 0.35 + 0.3 * rng.uniform());
      m.initial.push_back(p);
    }
    m.bodies.push_back({"plasticine", 0, 0, kParticles, 0.5 / 64 * 0.5 / 64});  // PlasticineLab's (dx / 2)^2
    PrimitiveSpec sphere;
    sphere.shape.kind = ShapeKind::sphere;
    sphere.shape.radius = 0.04;
    sphere.position = Vec3(0.5, 0.19, 0.5);
    sphere.softness = 666.0;
    sphere.motion = PrimitiveMotion::translate;
    sphere.action_axes = {0, 1, 2};
    sphere.action_scale = {0.02, 0.02, 0.02};
    m.primitives = {sphere};
    m.finalize("bench_mpm");
    return m;
  }();
  return model;
}

// down into the plasticine for half the episode, then sideways and up
std::vector<double> actions(int env_steps) {
  std::vector<double> a(3 * env_steps);
  for (int k = 0; k < env_steps; ++k) {
    a[3 * k] = k < kEnvSteps / 2 ? 0.0 : 0.5;
    a[3 * k + 1] = k < kEnvSteps / 2 ? -0.4 : 0.2;
    a[3 * k + 2] = 0.1;
  }
  return a;
}

PhaseTimes forward_phases, gradient_phases, gradient_taped_phases, forward_scalar_phases, gradient_scalar_phases;

// tape: the bytes of substep tapes the forward pass may keep (episode.hpp; 0 recomputes every env
// step in the reverse pass, kTapeEverything keeps them all)
void run(benchmark::State& state, int env_steps, bool gradient, PhaseTimes* phases, SimdPath path = default_lane_path(),
         std::size_t tape = 0) {
  const MpmModel& m = plb_sized_model();
  const testing::SmoothObjective objective;
  ThreadTeam team(static_cast<int>(state.range(0)));
  MpmWorkspace ws(m);
  ws.lanes = path;
  const auto a = actions(env_steps);
  std::vector<double> g(a.size());
  if (gradient) run_episode_with_grad(m, ws, team, a, env_steps, objective, g, tape);  // size the buffers
  PhaseTimes times;
  ws.phase_times = &times;
  for (auto _ : state) {
    const double loss = gradient ? run_episode_with_grad(m, ws, team, a, env_steps, objective, g, tape)
                                 : run_episode(m, ws, team, a, env_steps, objective);
    benchmark::DoNotOptimize(loss);
  }
  if (phases && state.range(0) == 1) {
    *phases = times;
    const double n = static_cast<double>(state.iterations());
    for (double* t : {&phases->bin, &phases->stress, &phases->p2g, &phases->grid, &phases->g2p, &phases->reverse_g2p,
                      &phases->reverse_grid, &phases->reverse_particles, &phases->other})
      *t /= n;
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(kParticles) * env_steps * m.config.substeps);
}

void BM_ForwardEpisodeFull(benchmark::State& s) { run(s, kEnvSteps, false, &forward_phases); }
void BM_GradientEpisodeFull(benchmark::State& s) { run(s, kEnvSteps, true, &gradient_phases); }
void BM_GradientEpisodeTapedFull(benchmark::State& s) {
  run(s, kEnvSteps, true, &gradient_taped_phases, default_lane_path(), kTapeEverything);
}
void BM_ForwardEpisodeScalarFull(benchmark::State& s) {
  run(s, kEnvSteps, false, &forward_scalar_phases, SimdPath::scalar);
}
void BM_GradientEpisodeScalarFull(benchmark::State& s) {
  run(s, kEnvSteps, true, &gradient_scalar_phases, SimdPath::scalar);
}
// Alternates the lanes and the scalar path env step by env step within forward episodes (the paths
// give the same bits, so the trajectory is the one of either) and times each env step: both paths
// then run under the same load, which matters on a shared machine. Seconds per path in `seconds`.
class AlternatingPaths : public EpisodeObserver {
 public:
  AlternatingPaths(MpmWorkspace& ws, SimdPath lanes) : ws_(ws), paths_{lanes, SimdPath::scalar} {}
  void at_step(int step, const std::vector<Particle>&, const std::vector<Pose>&) override {
    const auto now = std::chrono::steady_clock::now();
    if (step > 0) seconds[current_] += std::chrono::duration<double>(now - last_).count();
    current_ = step % 2;
    ws_.lanes = paths_[current_];
    last_ = std::chrono::steady_clock::now();
  }
  double seconds[2] = {0.0, 0.0};  // lanes, scalar

 private:
  MpmWorkspace& ws_;
  SimdPath paths_[2];
  int current_ = 0;
  std::chrono::steady_clock::time_point last_;
};

double alternating_lanes_seconds = 0.0, alternating_scalar_seconds = 0.0;

void BM_ForwardAlternatingPathsFull(benchmark::State& state) {
  const MpmModel& m = plb_sized_model();
  const testing::SmoothObjective objective;
  MpmWorkspace ws(m);
  AlternatingPaths paths(ws, default_lane_path());
  ws.observer = &paths;
  const auto a = actions(kEnvSteps);
  for (auto _ : state) benchmark::DoNotOptimize(run_episode(m, ws, serial_team(), a, kEnvSteps, objective));
  const double n = static_cast<double>(state.iterations());
  alternating_lanes_seconds = paths.seconds[0] / n;
  alternating_scalar_seconds = paths.seconds[1] / n;
}
BENCHMARK(BM_ForwardAlternatingPathsFull)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// The same for gradients: gradient episodes of 5 env steps, the paths taking turns, 3 each.
double alternating_gradient_lanes_seconds = 0.0, alternating_gradient_scalar_seconds = 0.0;

void BM_GradientAlternatingPathsFull(benchmark::State& state) {
  constexpr int kSteps = 5, kRounds = 3;
  const MpmModel& m = plb_sized_model();
  const testing::SmoothObjective objective;
  MpmWorkspace ws(m);
  const auto a = actions(kSteps);
  std::vector<double> g(a.size());
  run_episode_with_grad(m, ws, serial_team(), a, kSteps, objective, g);  // size the buffers
  double seconds[2] = {0.0, 0.0};
  for (auto _ : state)
    for (int r = 0; r < 2 * kRounds; ++r) {
      ws.lanes = r % 2 == 0 ? default_lane_path() : SimdPath::scalar;
      const auto start = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(run_episode_with_grad(m, ws, serial_team(), a, kSteps, objective, g));
      seconds[r % 2] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  const double n = static_cast<double>(state.iterations()) * kRounds;
  alternating_gradient_lanes_seconds = seconds[0] / n;
  alternating_gradient_scalar_seconds = seconds[1] / n;
}
BENCHMARK(BM_GradientAlternatingPathsFull)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

void BM_ForwardOneEnvStep(benchmark::State& s) { run(s, 1, false, nullptr); }
void BM_ForwardOneEnvStepScalar(benchmark::State& s) { run(s, 1, false, nullptr, SimdPath::scalar); }
void BM_GradientOneEnvStep(benchmark::State& s) { run(s, 1, true, nullptr); }
void BM_GradientOneEnvStepScalar(benchmark::State& s) { run(s, 1, true, nullptr, SimdPath::scalar); }
BENCHMARK(BM_ForwardEpisodeFull)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_GradientEpisodeFull)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_GradientEpisodeTapedFull)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ForwardEpisodeScalarFull)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_GradientEpisodeScalarFull)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ForwardOneEnvStep)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ForwardOneEnvStepScalar)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void fluid_rollouts(benchmark::State& state, bool gradient) {
  const auto env = make_env("fluid-h5");
  const std::vector<double> x = {0.5, -1.0, 0.6, -1.0, 0.5, 0.2, -0.3, 1.0, -0.3, 1.0};
  std::vector<double> g(x.size());
  const auto ws = env->make_workspace();
  env->loss_and_grad(x, g, *ws, serial_team());  // the first rollout sizes the buffers
  const perf::AllocationCounter allocations;
  for (auto _ : state)
    benchmark::DoNotOptimize(gradient ? env->loss_and_grad(x, g, *ws, serial_team())
                                      : env->loss(x, *ws, serial_team()));
  allocations.report(state);
}
void BM_FluidH5Forward(benchmark::State& s) { fluid_rollouts(s, false); }
void BM_FluidH5Gradient(benchmark::State& s) { fluid_rollouts(s, true); }
BENCHMARK(BM_FluidH5Forward)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FluidH5Gradient)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GradientOneEnvStep)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GradientOneEnvStepScalar)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// peak RSS (MB) of a child process that builds the model and runs one episode
double child_peak_rss_mb(bool gradient) {
  const pid_t pid = fork();
  if (pid == 0) {
    const MpmModel& m = plb_sized_model();
    const testing::SmoothObjective objective;
    MpmWorkspace ws(m);
    const auto a = actions(kEnvSteps);
    std::vector<double> g(a.size());
    const double loss = gradient ? run_episode_with_grad(m, ws, serial_team(), a, kEnvSteps, objective, g)
                                 : run_episode(m, ws, serial_team(), a, kEnvSteps, objective);
    _exit(std::isfinite(loss) ? 0 : 1);
  }
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  return ru.ru_maxrss / 1024.0;
}

// the CPU's model name (/proc/cpuinfo), "?" where there is none
std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  return "?";
}

void print_phases(const char* what, const PhaseTimes& t) {
  const double total =
      t.bin + t.stress + t.p2g + t.grid + t.g2p + t.reverse_g2p + t.reverse_grid + t.reverse_particles + t.other;
  if (total <= 0.0) return;
  std::printf("%s phases (1 thread, s): stress %.2f, p2g %.2f, g2p %.2f, grid %.2f, binning %.2f", what, t.stress,
              t.p2g, t.g2p, t.grid, t.bin);
  if (t.reverse_particles > 0.0)
    std::printf(", reverse: particles %.2f, g2p^T %.2f, grid^T %.2f", t.reverse_particles, t.reverse_g2p,
                t.reverse_grid);
  std::printf(", tapes/checkpoints %.2f; total %.2f\n", t.other, total);
}

}  // namespace

int main(int argc, char** argv) {
  const bool full = [&] {
    for (int i = 1; i < argc; ++i)
      if (std::string(argv[i]).find("-Full") != std::string::npos) return false;
    return true;
  }();
  const double rss_forward = full ? child_peak_rss_mb(false) : 0.0;
  const double rss_gradient = full ? child_peak_rss_mb(true) : 0.0;
  return perf::run_benchmarks(argc, argv, [&](const perf::TimingReporter& reporter) {
    const double f1 = reporter.seconds("BM_ForwardEpisodeFull/1/iterations:1/real_time");
    const double f2 = reporter.seconds("BM_ForwardEpisodeFull/2/iterations:1/real_time");
    const double g1 = reporter.seconds("BM_GradientEpisodeFull/1/iterations:1/real_time");
    const double g2 = reporter.seconds("BM_GradientEpisodeFull/2/iterations:1/real_time");
    const double gt = reporter.seconds("BM_GradientEpisodeTapedFull/1/iterations:1/real_time");
    const double fs = reporter.seconds("BM_ForwardEpisodeScalarFull/1/iterations:1/real_time");
    const double gs = reporter.seconds("BM_GradientEpisodeScalarFull/1/iterations:1/real_time");
    const double step = reporter.seconds("BM_ForwardOneEnvStep/1/real_time");
    const double step_scalar = reporter.seconds("BM_ForwardOneEnvStepScalar/1/real_time");
    const double gstep = reporter.seconds("BM_GradientOneEnvStep/1/real_time");
    const double gstep_scalar = reporter.seconds("BM_GradientOneEnvStepScalar/1/real_time");
    const double substeps = static_cast<double>(kEnvSteps) * plb_sized_model().config.substeps;
    const char* lanes = simd_path_name(default_lane_path());
    std::printf("\nCPU: %s; lanes path: %s (scalar forced by the *Scalar* benchmarks)\n", cpu_model().c_str(), lanes);
    if (alternating_lanes_seconds > 0.0)
      std::printf(
          "forward episode alternating the paths env step by env step (25 each, same load): %s %.2f s, "
          "scalar %.2f s: %.2fx\n",
          lanes, alternating_lanes_seconds, alternating_scalar_seconds,
          alternating_scalar_seconds / alternating_lanes_seconds);
    if (alternating_gradient_lanes_seconds > 0.0)
      std::printf(
          "gradient episodes of 5 env steps, the paths taking turns (3 each): %s %.2f s, scalar %.2f s: "
          "%.2fx\n",
          lanes, alternating_gradient_lanes_seconds, alternating_gradient_scalar_seconds,
          alternating_gradient_scalar_seconds / alternating_gradient_lanes_seconds);
    if (step > 0.0 && step_scalar > 0.0)
      std::printf("one env step, %s lanes against scalar: forward %.2fx", lanes, step_scalar / step);
    if (gstep > 0.0 && gstep_scalar > 0.0) std::printf(", gradient %.2fx", gstep_scalar / gstep);
    if (step > 0.0 && step_scalar > 0.0) std::printf("\n");
    if (f1 > 0.0) {
      std::printf("\nmodel: %d particles, %dx%dx%d grid, dt %g, %.0f substeps\n", kParticles,
                  plb_sized_model().config.grid[0], plb_sized_model().config.grid[1], plb_sized_model().config.grid[2],
                  plb_sized_model().config.dt, substeps);
      std::printf("forward: %.2f s = %.2f M particle-substeps/s (1 thread)\n", f1, kParticles * substeps / f1 / 1e6);
      if (g1 > 0.0) std::printf("gradient episode: %.2f s = %.2fx the forward (1 thread)\n", g1, g1 / f1);
      if (gt > 0.0)
        std::printf("gradient episode with every substep's tape kept: %.2f s = %.2fx the forward (1 thread)\n", gt,
                    gt / f1);
      if (f2 > 0.0)
        std::printf("2 threads: forward %.2fx, gradient %.2fx one thread\n", f1 / f2, g2 > 0 ? g1 / g2 : 0.0);
      if (fs > 0.0)
        std::printf("scalar path: forward %.2f s = %.2f M particle-substeps/s, gradient %.2f s (1 thread)\n", fs,
                    kParticles * substeps / fs / 1e6, gs);
      if (fs > 0.0) std::printf("%s lanes against scalar, 1 thread: forward %.2fx", lanes, fs / f1);
      if (fs > 0.0 && gs > 0.0 && g1 > 0.0) std::printf(", gradient %.2fx", gs / g1);
      if (fs > 0.0) std::printf("\n");
      print_phases("forward", forward_phases);
      print_phases("gradient", gradient_phases);
      print_phases("gradient, taped,", gradient_taped_phases);
      print_phases("forward, scalar path,", forward_scalar_phases);
      print_phases("gradient, scalar path,", gradient_scalar_phases);
    }
    if (full)
      std::printf(
          "peak RSS of a process running one episode: forward %.0f MB, gradient %.0f MB (full history of "
          "the particle states: %.0f MB)\n",
          rss_forward, rss_gradient, substeps * kParticles * sizeof(Particle) / 1e6);
  });
}
