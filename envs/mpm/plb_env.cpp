#include "envs/mpm/plb_env.hpp"

#include <algorithm>
#include <limits>
#include <optional>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "envs/core/horizon_name.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/substep.hpp"

namespace dsb::mpm {

namespace {

int commands_per_step(const PlbTask& task) {
  int d = 0;
  for (const auto& p : task.primitives) d += p.action_dim();
  return d;
}

EnvInfo plb_info(std::string name, const PlbConfig& cfg) {
  cfg.validate();
  const PlbTask& task = *find_plb_task(cfg.task);
  int particles = 0;
  for (const auto& s : task.shapes) particles += s.particles;
  EnvInfo info;
  info.name = std::move(name);
  info.dim = cfg.segments * commands_per_step(task);
  info.differentiable = true;
  info.rl = true;
  info.threaded = true;
  // `harness calibrate` on one core (2-core EPYC, binary f21b88f, lanes and tape), the seven tasks
  // of 10,000 particles: a gradient episode 8.4-11.8 s (median 9.4), a forward one 2.6-3.4 s (median
  // 2.8); scaled by the particles and the horizon
  info.cost_hint_s = 9.4 * particles / 10000.0 * cfg.env_steps / 50.0;
  info.cost_hint_forward_s = 2.8 * particles / 10000.0 * cfg.env_steps / 50.0;
  info.metric = "soft_iou";
  return info;
}

// Per-env-step interface: the action is every manipulator's commands of one env step.
class PlbRl : public RlEnv {
 public:
  explicit PlbRl(const PlbEnv& env)
      : env_(env),
        ws_(env.model().mpm),
        scratch_(env.model().mpm),
        objective_(env.model(), env.plb_config(), scratch_) {
    reset();
  }
  int observation_dim() const override {
    return 6 * observed() + 7 * static_cast<int>(env_.model().mpm.primitives.size());
  }
  int action_dim() const override { return env_.model().mpm.action_dim(); }
  int horizon() const override { return env_.plb_config().env_steps; }
  void reset() override {
    ws_.reset_state(env_.model().mpm);
    step_ = 0;
    loss_ = 0.0;
    scratch_.final_iou = std::numeric_limits<double>::quiet_NaN();
  }
  // the observed particles' positions and velocities (every stride()-th), then each primitive's
  // position and quaternion (w, x, y, z)
  std::vector<double> observe() const override {
    std::vector<double> o;
    const int k = observed();
    for (int i = 0; i < k; ++i) {
      const Particle& p = ws_.particles[static_cast<std::size_t>(i) * stride()];
      o.insert(o.end(), {p.x.x(), p.x.y(), p.x.z(), p.v.x(), p.v.y(), p.v.z()});
    }
    for (const auto& pose : ws_.poses)
      o.insert(o.end(), {pose.p.x(), pose.p.y(), pose.p.z(), pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z()});
    return o;
  }
  void step(std::span<const double> action) override {
    if (done()) return;
    std::vector<double> a(action.begin(), action.end());
    for (auto& v : a) v = std::clamp(v, -1.0, 1.0);
    for (int s = 0; s < env_.model().mpm.config.substeps; ++s)
      substep(env_.model().mpm, ws_, serial_team(), a.data(), nullptr);
    loss_ = state_is_finite(ws_.particles, serial_team())
        ? loss_ + objective_.step_loss(step_, ws_.particles, ws_.poses, serial_team())
        : std::numeric_limits<double>::quiet_NaN();
    ++step_;
  }
  bool done() const override { return step_ >= horizon() || std::isnan(loss_); }
  double final_loss() const override { return loss_; }
  // the soft IoU with the target after the last env step (the objective sets it there)
  double final_metric() const override { return std::isnan(loss_) ? loss_ : scratch_.final_iou; }

 private:
  // PlasticineLab's subsampling: particles 0, s, 2s, ... with s = N / observed_particles (integer
  // division, at least 1), ceil(N / s) of them: 200 of 10,000 or 6,000, but 205 of TripleMove's 9,999 (s = 49)
  int stride() const { return std::max(1, env_.model().mpm.particles() / env_.plb_config().observed_particles); }
  int observed() const { return (env_.model().mpm.particles() + stride() - 1) / stride(); }
  const PlbEnv& env_;
  MpmWorkspace ws_;
  PlbLossScratch scratch_;
  PlbObjective objective_;
  int step_ = 0;
  double loss_ = 0.0;
};

}  // namespace

PlbEnv::PlbEnv(std::string name, PlbConfig cfg)
    : ConfigModelEnv(plb_info(std::move(name), cfg), cfg, build_plb_model),
      action_dim_(commands_per_step(*find_plb_task(cfg_.task))) {}

std::unique_ptr<Workspace> PlbEnv::make_workspace() const {
  auto ws = std::make_unique<PlbWorkspace>(model().mpm);
  ws->actions.resize(static_cast<std::size_t>(cfg_.env_steps) * action_dim_);
  ws->actions_bar.resize(ws->actions.size());
  return ws;
}

std::unique_ptr<RlEnv> PlbEnv::make_rl() const { return std::make_unique<PlbRl>(*this); }

double PlbEnv::episode_metric(const Workspace& ws) const { return static_cast<const PlbWorkspace&>(ws).loss.final_iou; }

void PlbEnv::actions(std::span<const double> x, std::vector<double>& out) const {
  out.resize(static_cast<std::size_t>(cfg_.env_steps) * action_dim_);
  const int per = cfg_.steps_per_segment();
  for (int k = 0; k < cfg_.env_steps; ++k)
    std::copy_n(x.begin() + static_cast<std::ptrdiff_t>(k / per) * action_dim_, action_dim_,
                out.begin() + static_cast<std::ptrdiff_t>(k) * action_dim_);
}

std::vector<double> plb_reference_actions(const PlbTask& task, int env_steps) {
  const int d = commands_per_step(task);
  std::vector<double> a;
  for (const auto& phase : task.reference)
    for (int s = 0; s < phase.steps; ++s) a.insert(a.end(), phase.actions.begin(), phase.actions.end());
  a.resize(static_cast<std::size_t>(env_steps) * d, 0.0);
  return a;
}

std::vector<double> PlbEnv::reference_actions() const {
  return plb_reference_actions(*find_plb_task(cfg_.task), cfg_.env_steps);
}

double PlbEnv::rollout(std::span<const double> x, Workspace& workspace, ThreadTeam& team) const {
  auto& ws = static_cast<PlbWorkspace&>(workspace);
  actions(x, ws.actions);
  ws.loss.final_iou = std::numeric_limits<double>::quiet_NaN();
  const PlbObjective objective(model(), cfg_, ws.loss);
  return run_episode(model().mpm, ws.mpm, team, ws.actions, cfg_.env_steps, objective);
}

double PlbEnv::rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& workspace,
                                 ThreadTeam& team) const {
  auto& ws = static_cast<PlbWorkspace&>(workspace);
  actions(x, ws.actions);
  ws.loss.final_iou = std::numeric_limits<double>::quiet_NaN();
  const PlbObjective objective(model(), cfg_, ws.loss);
  const double loss = run_episode_with_grad(model().mpm, ws.mpm, team, ws.actions, cfg_.env_steps, objective,
                                            ws.actions_bar, ws.tape_memory_bytes);
  // each param drives its manipulator command over its segment's env steps
  std::fill(grad.begin(), grad.end(), 0.0);
  const int per = cfg_.steps_per_segment();
  for (int k = 0; k < cfg_.env_steps; ++k)
    for (int c = 0; c < action_dim_; ++c)
      grad[(k / per) * action_dim_ + c] += ws.actions_bar[static_cast<std::size_t>(k) * action_dim_ + c];
  return loss;
}

namespace {

// the config of "plb-TASK" or "plb-TASK-hN"; nullopt when the name is not one (UsageError for a
// malformed horizon, as parse_horizon_name says)
std::optional<PlbConfig> plb_config_of_name(const std::string& requested) {
  if (requested.rfind("plb-", 0) != 0) return std::nullopt;
  const std::string rest = requested.substr(4);
  const std::string task = rest.substr(0, rest.rfind("-h"));  // the whole rest when there is no -h
  if (!find_plb_task(task)) return std::nullopt;
  PlbConfig cfg = plb_config(task);
  if (task != rest) {
    const auto steps = parse_horizon_name(requested, "plb-" + task, cfg.env_steps, cfg.segments);
    if (!steps) return std::nullopt;
    cfg.env_steps = *steps;
  }
  return cfg;
}

}  // namespace

EnvFamily plb_family() {
  EnvFamily f;
  f.pattern = "plb-NAME";
  f.description =
      "PlasticineLab tasks on the MPM engine (64^3, dt 1e-4, 19 x 50 substeps, von Mises); "
      "plb-NAME-hN: the first N env steps of 50 (N = 5..45, a multiple of 5)";
  for (const auto& t : plb_tasks()) f.grid_names.push_back("plb-" + t.name);
  f.try_make = [](const std::string& requested) -> std::unique_ptr<Env> {
    auto cfg = plb_config_of_name(requested);
    return cfg ? std::make_unique<PlbEnv>(requested, *cfg) : nullptr;
  };
  f.options = {{"target",
                "a PlasticineLab-format .npy target grid (float64 or float32, C order, shape (64, 64, 64), "
                "node (i, j, k) at (i, j, k)/64; e.g. its assets' Pinch3D-v1.npy) in place of ours; a run "
                "key by the hash of its values",
                "data/targets/plb-NAME.txt.gz (our reference motion's final state)", true}};
  f.make_with_options = [](const std::string& requested, const EnvOptions& options) -> std::unique_ptr<Env> {
    PlbConfig cfg = *plb_config_of_name(requested);
    if (const auto t = options.find("target"); t != options.end()) {
      try {
        cfg.target_file = std::make_shared<const PlbTargetFile>(read_plb_target(t->second, cfg.mpm));
      } catch (const UsageError& e) {
        throw UsageError(requested + ".target: " + e.what());
      }
    }
    return std::make_unique<PlbEnv>(requested, cfg);
  };
  return f;
}

}  // namespace dsb::mpm
