#include "envs/cloth/swing_env.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/det_math.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "envs/cloth/cloth_task_setup.hpp"

namespace dsb::cloth {

namespace {

constexpr int kPatches = 4;  // per side

int param_dim(SwingParams p) { return p == SwingParams::stiffness ? kPatches * kPatches : 3; }

// per-spring stiffness: k_s = ratio_s exp(log k_low + (x_p + 1) / 2 (log k_high - log k_low))
void stiffness_of(const SwingModel& m, std::span<const double> x, std::vector<double>& k) {
  double patch_k[kPatches * kPatches];
  for (int p = 0; p < kPatches * kPatches; ++p)
    patch_k[p] = dm::exp(m.log_k_low + 0.5 * (x[p] + 1.0) * (m.log_k_high - m.log_k_low));
  k.resize(m.spring_patch.size());
  for (std::size_t s = 0; s < k.size(); ++s) k[s] = m.spring_ratio[s] * patch_k[m.spring_patch[s]];
}

// at rest in the rest positions; the velocity tasks give every vertex v0 = v_low + (x + 1) / 2 (v_high - v_low)
void initial_state_of(const SwingConfig& cfg, SwingParams params, const SwingModel& m, std::span<const double> x,
                      ClothState& s) {
  s.x = m.cloth.rest_position;
  Vec3 v0 = Vec3::Zero();
  if (params == SwingParams::velocity)
    for (int c = 0; c < 3; ++c) v0(c) = cfg.v_low[c] + 0.5 * (x[c] + 1.0) * (cfg.v_high[c] - cfg.v_low[c]);
  s.v.assign(m.cloth.rest_position.size(), v0);
}

// the forward episode (loss path and target generation): steps of cloth_step from s
void run_forward(const SwingModel& m, std::span<const double> stiffness, ClothState& s, std::vector<Vec3>& force) {
  force.resize(m.cloth.rest_position.size());
  const ClothInputs in{stiffness, m.anchor_path};
  for (int t = 0; t < m.steps; ++t) cloth_step(m.cloth, in, t, s, force);
}

bool finite_state(const ClothState& s) {
  for (std::size_t i = 0; i < s.x.size(); ++i)
    if (!s.x[i].allFinite() || !s.v[i].allFinite()) return false;
  return true;
}

SwingModel build_swing_model(const SwingConfig& cfg, SwingParams params) {
  cfg.validate();
  SwingModel m;
  // flat cloth at start_height: vertex (col, row) at (-width/2 + col du, start_height, -height + row dv)
  m.cloth =
      build_grid(flat_grid_spec(cfg, cfg.width, cfg.height, Vec3(-0.5 * cfg.width, cfg.start_height, -cfg.height)));
  ClothModel& c = m.cloth;
  const int W = cfg.cols, H = cfg.rows;
  // the two held corners: the front edge z = 0 (row H - 1), columns 0 and W - 1
  const int release = cfg.release_step();
  c.anchors = {{(H - 1) * W, release}, {(H - 1) * W + W - 1, release}};
  set_floor_world(c, cfg);
  m.steps = cfg.steps();
  m.corners = {0, W - 1, (H - 1) * W, H * W - 1};
  m.observed = grid_subsample_3x3(W, H);
  // scripted swing of the held corners (only rows up to the release are read)
  m.anchor_path = anchor_path_from(c, m.steps, [&](int a, double t) -> Vec3 {
    const double tau = std::min(t / cfg.swing_time, 1.0);
    const double angle = std::numbers::pi * tau;
    const Vec3& p0 = c.rest_position[c.anchors[a].vertex];
    return p0 + Vec3(0.0, cfg.lift * dm::sin(angle), cfg.forward * 0.5 * (1.0 - dm::cos(angle)));
  });
  // patches by each spring's midpoint in grid coordinates (integer arithmetic, no ties to round)
  m.spring_patch.resize(c.springs.size());
  m.spring_ratio.resize(c.springs.size());
  for (std::size_t s = 0; s < c.springs.size(); ++s) {
    const Spring& sp = c.springs[s];
    const int ci = sp.i % W, ri = sp.i / W, cj = sp.j % W, rj = sp.j / W;
    const int pc = std::min(kPatches - 1, kPatches * (ci + cj) / (2 * (W - 1)));
    const int pr = std::min(kPatches - 1, kPatches * (ri + rj) / (2 * (H - 1)));
    m.spring_patch[s] = pr * kPatches + pc;
    m.spring_ratio[s] = sp.kind == SpringKind::shear ? cfg.shear_ratio
        : sp.kind == SpringKind::bending             ? cfg.bending_ratio
                                                     : 1.0;
  }
  m.log_k_low = dm::log(cfg.k_low);
  m.log_k_high = dm::log(cfg.k_high);
  const std::vector<double> middle(kPatches * kPatches, 0.0);
  stiffness_of(m, middle, m.fixed_stiffness);
  // targets: the final state at the reference params, by the loss path's own forward episode
  std::vector<double> ref = params == SwingParams::stiffness
      ? cfg.stiffness_reference
      : std::vector<double>(cfg.velocity_reference.begin(), cfg.velocity_reference.end());
  std::vector<double> k;
  if (params == SwingParams::stiffness)
    stiffness_of(m, ref, k);
  else
    k = m.fixed_stiffness;
  ClothState s;
  initial_state_of(cfg, params, m, ref, s);
  std::vector<Vec3> force;
  run_forward(m, k, s, force);
  if (!finite_state(s))
    throw ConfigError("swing", "stiffness_reference/velocity_reference", "the reference episode blew up");
  m.target = s.x;
  m.target_com = centre_of_mass(c, s.x);
  return m;
}

EnvInfo swing_info(std::string name, SwingParams params, const SwingConfig& cfg) {
  cfg.validate();  // at construction, although the model is built on first use
  EnvInfo info;
  info.name = std::move(name);
  info.dim = param_dim(params);
  info.differentiable = true;
  info.rl = true;
  // `harness calibrate` on the 2-core EPYC (binary f21b88f), the six swing envs: a gradient episode
  // 21-44 ms on one core, a forward one 8.3-13 ms
  info.cost_hint_s = 0.03;
  info.smoothness = Smoothness::piecewise;  // the floor's contact
  info.cost_hint_forward_s = 0.011;
  return info;
}

// The RL view: reset shows the cloth at rest, one step runs the episode with the action as params.
class SwingRl : public RlEnv {
 public:
  explicit SwingRl(const SwingEnv& env) : env_(env) {
    ws_ = env.make_workspace();
    reset();
  }
  int observation_dim() const override { return 61; }
  int action_dim() const override { return env_.dim(); }
  int horizon() const override { return 1; }
  void reset() override {
    state_.x = env_.model().cloth.rest_position;
    state_.v.assign(state_.x.size(), Vec3::Zero());
    done_ = false;
    loss_ = std::numeric_limits<double>::quiet_NaN();
  }
  // 3 x 3 vertex positions and velocities, the held corners' positions, time (0 or 1)
  std::vector<double> observe() const override {
    const SwingModel& m = env_.model();
    std::vector<double> o;
    o.reserve(61);
    append_vertex_states(o, state_, m.observed);
    for (const Anchor& a : m.cloth.anchors)
      for (int k = 0; k < 3; ++k) o.push_back(state_.x[a.vertex](k));
    o.push_back(done_ ? 1.0 : 0.0);
    return o;
  }
  void step(std::span<const double> action) override {
    if (done_) return;
    std::vector<double> x(action.begin(), action.end());
    for (double& v : x) v = std::clamp(v, -1.0, 1.0);
    // the value path itself (rollout), so the loss is loss(x)'s bits
    loss_ = env_.loss(x, *ws_, serial_team());
    state_ = static_cast<const SwingWorkspace&>(*ws_).state;
    done_ = true;
  }
  bool done() const override { return done_; }
  double final_loss() const override { return loss_; }

 private:
  const SwingEnv& env_;
  std::unique_ptr<Workspace> ws_;
  ClothState state_;
  bool done_ = false;
  double loss_ = 0.0;
};

}  // namespace

std::unique_ptr<RlEnv> SwingEnv::make_rl() const { return std::make_unique<SwingRl>(*this); }

SwingEnv::SwingEnv(std::string name, SwingParams params, SwingLoss loss, SwingConfig cfg)
    : ConfigModelEnv(swing_info(std::move(name), params, cfg), cfg,
                     [params](const SwingConfig& c) { return build_swing_model(c, params); }),
      params_(params),
      loss_(loss) {}

nlohmann::json SwingEnv::config() const {
  nlohmann::json j = cfg_.to_json();
  j["params"] = params_ == SwingParams::stiffness
      ? "16 patch log-stiffnesses: log k = log k_low + (x + 1) / 2 (log k_high - log k_low)"
      : "initial velocity of every vertex: v = v_low + (x + 1) / 2 (v_high - v_low)";
  j["loss"] = loss_ == SwingLoss::single ? "|final centre of mass - target centre of mass|"
      : loss_ == SwingLoss::corner       ? "mean over the 4 corners of |final x - target x|"
                                         : "mean over all vertices of |final x - target x|";
  j["target"] = "final state of the rollout at the reference params (loss 0 there)";
  return j;
}

std::unique_ptr<Workspace> SwingEnv::make_workspace() const {
  const SwingModel& m = model();
  auto ws = std::make_unique<SwingWorkspace>();
  const int n = m.cloth.vertices();
  ws->tape.reset(n, static_cast<int>(m.cloth.springs.size()), m.steps);
  ws->force.resize(n);
  ws->stiffness.resize(m.cloth.springs.size());
  ws->final_bar.reset(n);
  return ws;
}

std::vector<double> SwingEnv::reference() const {
  if (params_ == SwingParams::stiffness) return cfg_.stiffness_reference;
  return {cfg_.velocity_reference.begin(), cfg_.velocity_reference.end()};
}

void SwingEnv::fill_stiffness(const SwingModel& m, std::span<const double> x, std::vector<double>& k) const {
  if (params_ == SwingParams::stiffness)
    stiffness_of(m, x, k);
  else
    k = m.fixed_stiffness;
}

void SwingEnv::fill_initial_state(const SwingModel& m, std::span<const double> x, ClothState& s) const {
  initial_state_of(cfg_, params_, m, x, s);
}

std::vector<double> SwingEnv::stiffness(std::span<const double> x) const {
  std::vector<double> k;
  fill_stiffness(model(), x, k);
  return k;
}

ClothState SwingEnv::initial_state(std::span<const double> x) const {
  ClothState s;
  fill_initial_state(model(), x, s);
  return s;
}

ClothState SwingEnv::final_state(std::span<const double> x) const {
  const SwingModel& m = model();
  std::vector<double> k;
  fill_stiffness(m, x, k);
  ClothState s;
  fill_initial_state(m, x, s);
  std::vector<Vec3> force;
  run_forward(m, k, s, force);
  return s;
}

double SwingEnv::final_loss(const ClothState& s) const {
  if (!finite_state(s)) return std::numeric_limits<double>::quiet_NaN();
  const SwingModel& m = model();
  switch (loss_) {
    case SwingLoss::single: return (centre_of_mass(m.cloth, s.x) - m.target_com).norm();
    case SwingLoss::corner: {
      double sum = 0.0;
      for (int v : m.corners) sum += (s.x[v] - m.target[v]).norm();
      return sum / 4.0;
    }
    case SwingLoss::mesh: {
      double sum = 0.0;
      for (std::size_t i = 0; i < s.x.size(); ++i) sum += (s.x[i] - m.target[i]).norm();
      return sum / static_cast<double>(s.x.size());
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::vector<char> SwingEnv::contact_pattern(std::span<const double> x) const {
  const SwingModel& m = model();
  std::vector<double> k;
  fill_stiffness(m, x, k);
  ClothState s0;
  fill_initial_state(m, x, s0);
  ClothTape tape;
  cloth_rollout(m.cloth, ClothInputs{k, m.anchor_path}, s0, m.steps, tape);
  const int n = m.cloth.vertices();
  std::vector<char> flags(std::size_t(m.steps) * n, 0);
  // the floor (the only surface) acted in step t, as cloth_step recorded it
  for (int t = 0; t < m.steps; ++t) {
    const auto acted = tape.contact(t);
    std::copy(acted.begin(), acted.end(), flags.begin() + std::size_t(t) * n);
  }
  return flags;
}

double SwingEnv::rollout(std::span<const double> x, Workspace& workspace, ThreadTeam&) const {
  auto& ws = static_cast<SwingWorkspace&>(workspace);
  const SwingModel& m = model();
  fill_stiffness(m, x, ws.stiffness);
  fill_initial_state(m, x, ws.state);
  run_forward(m, ws.stiffness, ws.state, ws.force);
  return final_loss(ws.state);
}

double SwingEnv::rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& workspace,
                                   ThreadTeam&) const {
  auto& ws = static_cast<SwingWorkspace&>(workspace);
  const SwingModel& m = model();
  const ClothModel& c = m.cloth;
  const int n = c.vertices();
  fill_stiffness(m, x, ws.stiffness);
  ClothState s0;
  fill_initial_state(m, x, s0);
  const ClothInputs in{ws.stiffness, m.anchor_path};
  // forward pass on the tape (the same steps as rollout())
  ws.state = cloth_rollout(c, in, s0, m.steps, ws.tape);
  const double loss = final_loss(ws.state);
  if (!std::isfinite(loss)) {
    std::fill(grad.begin(), grad.end(), std::numeric_limits<double>::quiet_NaN());
    return loss;
  }
  // dLoss/d(final positions): unit directions of the distances (0 at a zero distance)
  ws.final_bar.reset(n);
  auto unit = [](const Vec3& d) -> Vec3 {
    const double l = d.norm();
    return l > 0.0 ? Vec3(d / l) : Vec3::Zero();
  };
  switch (loss_) {
    case SwingLoss::single: {
      // d|c - c*|/dx_i = m_i / M (c - c*) / |c - c*|
      const Vec3 u = unit(centre_of_mass(c, ws.state.x) - m.target_com);
      double total = 0.0;
      for (int i = 0; i < n; ++i) total += c.mass[i];
      for (int i = 0; i < n; ++i) ws.final_bar.x[i] = (c.mass[i] / total) * u;
      break;
    }
    case SwingLoss::corner:
      for (int v : m.corners) ws.final_bar.x[v] = 0.25 * unit(ws.state.x[v] - m.target[v]);
      break;
    case SwingLoss::mesh:
      for (int i = 0; i < n; ++i) ws.final_bar.x[i] = unit(ws.state.x[i] - m.target[i]) / static_cast<double>(n);
      break;
  }
  // reverse pass through every step
  cloth_rollout_adjoint(c, in, ws.tape, ws.final_bar, nullptr, ws.grad);
  std::fill(grad.begin(), grad.end(), 0.0);
  if (params_ == SwingParams::stiffness) {
    // dL/dx_p = sum over the patch's springs of dL/dk_s k_s (log k_high - log k_low) / 2
    const double half_range = 0.5 * (m.log_k_high - m.log_k_low);
    for (std::size_t s = 0; s < c.springs.size(); ++s)
      grad[m.spring_patch[s]] += ws.grad.stiffness[s] * ws.stiffness[s] * half_range;
  } else {
    // every vertex starts with v0: dL/dv0 = sum_i dL/dv0_i, then the affine map's (v_high - v_low) / 2
    Vec3 sum = Vec3::Zero();
    for (int i = 0; i < n; ++i) sum += ws.grad.v0[i];
    for (int k = 0; k < 3; ++k) grad[k] = sum(k) * 0.5 * (cfg_.v_high[k] - cfg_.v_low[k]);
  }
  return loss;
}

EnvFamily swing_family() {
  EnvFamily f;
  f.pattern = "swing-{stiffness,velocity}-{single,corner,mesh}";
  f.description =
      "20 x 20 cm mass-spring cloth (9 x 9) held at two corners, swung forward and released onto the floor "
      "(dt 5e-4, 0.8 s); 16 patch log-stiffnesses or a 3-D initial velocity; targets from reference params";
  for (const char* p : {"stiffness", "velocity"})
    for (const char* l : {"single", "corner", "mesh"}) f.grid_names.push_back(std::string("swing-") + p + "-" + l);
  f.try_make = [](const std::string& requested) -> std::unique_ptr<Env> {
    const std::string prefix = "swing-";
    if (requested.rfind(prefix, 0) != 0) return nullptr;
    const std::string rest = requested.substr(prefix.size());
    const auto dash = rest.find('-');
    const std::string p = rest.substr(0, dash), l = dash == std::string::npos ? "" : rest.substr(dash + 1);
    const bool p_ok = p == "stiffness" || p == "velocity";
    const bool l_ok = l == "single" || l == "corner" || l == "mesh";
    if (!p_ok || !l_ok)
      throw UsageError("unknown env '" + requested + "' (swing-{stiffness,velocity}-{single,corner,mesh})");
    const SwingParams params = p == "stiffness" ? SwingParams::stiffness : SwingParams::velocity;
    const SwingLoss loss = l == "single" ? SwingLoss::single : l == "corner" ? SwingLoss::corner : SwingLoss::mesh;
    return std::make_unique<SwingEnv>(requested, params, loss, SwingConfig{});
  };
  return f;
}

}  // namespace dsb::cloth
