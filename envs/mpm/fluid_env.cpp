#include "envs/mpm/fluid_env.hpp"

#include <algorithm>
#include <limits>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "envs/core/horizon_name.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/fluid_model.hpp"
#include "envs/mpm/substep.hpp"

namespace dsb::mpm {

namespace {

constexpr int kActionsPerStep = 4;  // bowl (x, y), handle (x, y)

EnvInfo fluid_info(std::string name, const FluidConfig& cfg) {
  cfg.validate();
  EnvInfo info;
  info.name = std::move(name);
  info.dim = 2 * cfg.segments;
  info.differentiable = true;
  info.rl = true;
  info.threaded = true;
  // `harness calibrate` of the full task on one core (2-core EPYC, binary f21b88f, lanes and tape):
  // a gradient episode 2.76 s, a forward one 0.61 s; scaled by the horizon
  info.cost_hint_s = 2.76 * cfg.env_steps / 50.0;
  info.cost_hint_forward_s = 0.61 * cfg.env_steps / 50.0;
  info.metric = "cube_height";  // m above the tank floor after the last env step (above the rim: lifted out)
  return info;
}

// Per-env-step interface: the action is the ladle's (forward/back, up/down) speed in [-1, 1]^2.
class FluidRl : public RlEnv {
 public:
  FluidRl(const FluidEnv& env) : env_(env), ws_(env.model()), objective_(env.fluid_config(), env.model()) { reset(); }
  int observation_dim() const override { return 6; }
  int action_dim() const override { return 2; }
  int horizon() const override { return env_.fluid_config().env_steps; }
  void reset() override {
    ws_.reset_state(env_.model());
    step_ = 0;
    blown_up_ = false;
  }
  // The paper's "object and ladle positions": the cube's centre and the bowl's centre (m). The
  // ladle is kinematic: each env step moves it by the commanded speed (clamped to its box), with
  // no inertia and a fixed tilt, so its position is its whole state and nothing else of it is
  // needed to be Markov. The syrup's and the cube's particles are not observed (as in the paper):
  // no short observation of them is Markov, and the cube's velocity is left out with them.
  std::vector<double> observe() const override {
    const Vec3 c = cube_centre(env_.model(), ws_.particles);
    const Vec3& b = ws_.poses[0].p;
    return {c.x(), c.y(), c.z(), b.x(), b.y(), b.z()};
  }
  void step(std::span<const double> action) override {
    if (done()) return;
    const double ax = std::clamp(action[0], -1.0, 1.0), ay = std::clamp(action[1], -1.0, 1.0);
    const double a[kActionsPerStep] = {ax, ay, ax, ay};
    for (int s = 0; s < env_.model().config.substeps; ++s) substep(env_.model(), ws_, serial_team(), a, nullptr);
    if (!state_is_finite(ws_.particles, serial_team())) blown_up_ = true;
    ++step_;
  }
  bool done() const override { return step_ >= horizon() || blown_up_; }
  double final_loss() const override {
    if (blown_up_) return std::numeric_limits<double>::quiet_NaN();
    return objective_.final_loss(ws_.particles, ws_.poses);
  }
  // the cube's height above the tank floor after the last env step, as the rollout's metric
  double final_metric() const override {
    if (blown_up_ || step_ < horizon()) return std::numeric_limits<double>::quiet_NaN();
    return objective_.cube_height(ws_.particles);
  }

 private:
  const FluidEnv& env_;
  MpmWorkspace ws_;
  FluidObjective objective_;
  int step_ = 0;
  bool blown_up_ = false;
};

}  // namespace

FluidEnv::FluidEnv(std::string name, FluidConfig cfg)
    : ConfigModelEnv(fluid_info(std::move(name), cfg), cfg, build_fluid_model) {}

std::unique_ptr<Workspace> FluidEnv::make_workspace() const {
  auto ws = std::make_unique<FluidWorkspace>(model());
  ws->actions.resize(static_cast<std::size_t>(cfg_.env_steps) * kActionsPerStep);
  ws->actions_bar.resize(ws->actions.size());
  return ws;
}

std::unique_ptr<RlEnv> FluidEnv::make_rl() const { return std::make_unique<FluidRl>(*this); }

void FluidEnv::actions(std::span<const double> x, std::vector<double>& out) const {
  out.resize(static_cast<std::size_t>(cfg_.env_steps) * kActionsPerStep);
  const int per = cfg_.steps_per_segment();
  for (int k = 0; k < cfg_.env_steps; ++k) {
    const int s = k / per;
    double* a = out.data() + static_cast<std::size_t>(k) * kActionsPerStep;
    a[0] = a[2] = x[2 * s];
    a[1] = a[3] = x[2 * s + 1];
  }
}

std::vector<double> FluidEnv::rl_actions(std::span<const double> x) const {
  const int per = cfg_.steps_per_segment();
  std::vector<double> a(static_cast<std::size_t>(cfg_.env_steps) * 2);
  for (int k = 0; k < cfg_.env_steps; ++k) {
    a[2 * static_cast<std::size_t>(k)] = x[2 * (k / per)];
    a[2 * static_cast<std::size_t>(k) + 1] = x[2 * (k / per) + 1];
  }
  return a;
}

double FluidEnv::rollout(std::span<const double> x, Workspace& workspace, ThreadTeam& team) const {
  auto& ws = static_cast<FluidWorkspace&>(workspace);
  actions(x, ws.actions);
  const FluidObjective objective(cfg_, model());
  const double loss = run_episode(model(), ws.mpm, team, ws.actions, cfg_.env_steps, objective);
  ws.cube_height = objective.final_cube_height();
  return loss;
}

double FluidEnv::episode_metric(const Workspace& ws) const {
  return static_cast<const FluidWorkspace&>(ws).cube_height;
}

double FluidEnv::rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& workspace,
                                   ThreadTeam& team) const {
  auto& ws = static_cast<FluidWorkspace&>(workspace);
  actions(x, ws.actions);
  const FluidObjective objective(cfg_, model());
  const double loss = run_episode_with_grad(model(), ws.mpm, team, ws.actions, cfg_.env_steps, objective,
                                            ws.actions_bar, ws.tape_memory_bytes);
  ws.cube_height = objective.final_cube_height();
  // each param drives both primitives over its segment's env steps
  std::fill(grad.begin(), grad.end(), 0.0);
  const int per = cfg_.steps_per_segment();
  for (int k = 0; k < cfg_.env_steps; ++k) {
    const int s = k / per;
    const double* g = ws.actions_bar.data() + static_cast<std::size_t>(k) * kActionsPerStep;
    grad[2 * s] += g[0] + g[2];
    grad[2 * s + 1] += g[1] + g[3];
  }
  return loss;
}

std::vector<FluidEnv::TrajectoryPoint> FluidEnv::trajectory(std::span<const double> x, ThreadTeam& team) const {
  MpmWorkspace ws(model());
  std::vector<double> a;
  actions(x, a);
  ws.reset_state(model());
  std::vector<TrajectoryPoint> points{{cube_centre(model(), ws.particles), ws.poses[0].p}};
  for (int k = 0; k < cfg_.env_steps; ++k) {
    for (int s = 0; s < cfg_.mpm.substeps; ++s)
      substep(model(), ws, team, a.data() + static_cast<std::size_t>(k) * kActionsPerStep, nullptr);
    points.push_back({cube_centre(model(), ws.particles), ws.poses[0].p});
  }
  return points;
}

EnvFamily fluid_family() {
  EnvFamily f;
  f.pattern = "fluid";
  f.description =
      "MLS-MPM (9,834 particles, 400 substeps): a 2-DOF ladle scoops a sugar cube out of syrup in a 0.4 x 0.4 "
      "x 0.2 m tank, 5 segments x 2 speeds; fluid-hN: the first N env steps of 50 (N = 5..45, a multiple of 5)";
  f.grid_names = {"fluid"};
  f.try_make = [](const std::string& requested) -> std::unique_ptr<Env> {
    if (requested == "fluid") return std::make_unique<FluidEnv>("fluid", FluidConfig{});
    FluidConfig cfg;
    const auto steps = parse_horizon_name(requested, "fluid", cfg.env_steps, cfg.segments);
    if (!steps) return nullptr;
    cfg.env_steps = *steps;
    return std::make_unique<FluidEnv>(requested, cfg);
  };
  return f;
}

}  // namespace dsb::mpm
