#include "envs/cloth/flip_env.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/det_math.hpp"
#include "common/parallel.hpp"
#include "envs/cloth/cloth_task_setup.hpp"

namespace dsb::cloth {

namespace {

constexpr int kWaypoints = 5;
constexpr int kDim = 3 * kWaypoints;

bool finite_state(const ClothState& s) {
  for (std::size_t i = 0; i < s.x.size(); ++i)
    if (!s.x[i].allFinite() || !s.v[i].allFinite()) return false;
  return true;
}

Vec3 unit_or_zero(const Vec3& d) {
  const double l = d.norm();
  return l > 0.0 ? Vec3(d / l) : Vec3::Zero();
}

FlipModel build_flip_model(const FlipConfig& cfg) {
  cfg.validate();
  FlipModel m;
  // flat pancake at start_gap: vertex (col, row) at (-side/2 + col du, start_gap, -side/2 + row dv)
  GridSpec g = flat_grid_spec(cfg, cfg.side, cfg.side, Vec3(-0.5 * cfg.side, cfg.start_gap, -0.5 * cfg.side));
  g.structural_stiffness = cfg.structural_stiffness;
  g.shear_stiffness = cfg.shear_stiffness;
  g.bending_stiffness = cfg.bending_stiffness;
  m.cloth = build_grid(g);
  ClothModel& c = m.cloth;
  set_floor_world(c, cfg);
  m.stiffness = c.default_stiffness();
  m.steps = cfg.steps();
  m.segment_steps = cfg.segment_steps();
  const int W = cfg.cols, H = cfg.rows;
  m.corners = {0, W - 1, (H - 1) * W, H * W - 1};
  // targets: the start corners mirrored through the pan's axis (x -> -x), on the bottom (y 0); the
  // start pose is the identity, so world = local at t = 0
  for (int k = 0; k < 4; ++k) {
    const Vec3& p = c.rest_position[m.corners[k]];
    m.corner_target_local[k] = Vec3(-p.x(), 0.0, p.z());
  }
  m.observed = grid_subsample_3x3(W, H);
  return m;
}

EnvInfo flip_info(std::string name, const FlipConfig& cfg) {
  cfg.validate();  // at construction, although the model is built on first use
  EnvInfo info;
  info.name = std::move(name);
  info.dim = kDim;
  info.differentiable = true;
  info.rl = true;
  // `harness calibrate` on the 2-core EPYC (binary f21b88f): a gradient episode 41 ms on one core,
  // a forward one 11.5 ms
  info.cost_hint_s = 0.041;
  info.smoothness = Smoothness::piecewise;  // the pan's contact
  info.cost_hint_forward_s = 0.0115;
  return info;
}

// the pose a + alpha (b - a), per DOF
PanPose lerp(const PanPose& a, const PanPose& b, double alpha) {
  return {a.x + alpha * (b.x - a.x), a.y + alpha * (b.y - a.y), a.tilt + alpha * (b.tilt - a.tilt)};
}

// Per-interval interface: the action moves the pan's pose, linearly within the interval.
class FlipRl : public RlEnv {
 public:
  explicit FlipRl(const FlipEnv& env)
      : env_(env),
        pan_(std::make_shared<PanSurface>(env.flip_config().pan)),
        cloth_(cloth_with_pan(env.model(), pan_)),
        step_scale_(env.max_step()) {
    force_.resize(cloth_.vertices());
    reset();
  }
  int observation_dim() const override { return 61; }
  int action_dim() const override { return 3; }
  int horizon() const override { return env_.model().steps / env_.flip_config().control_steps; }
  void reset() override {
    const FlipModel& m = env_.model();
    pan_->set_path(std::vector<PanPose>(std::size_t(m.steps) + 1), cloth_.dt);
    state_ = rest_state(cloth_);
    pose_ = last_pose_ = PanPose{};
    t_ = 0;
    blown_up_ = false;
  }
  // 3 x 3 vertex positions and velocities, pan pose and its velocity over the last interval, time
  std::vector<double> observe() const override {
    const FlipModel& m = env_.model();
    std::vector<double> o;
    o.reserve(61);
    append_vertex_states(o, state_, m.observed);
    const double interval = env_.flip_config().control_steps * cloth_.dt;
    o.insert(o.end(),
             {pose_.x, pose_.y, pose_.tilt, (pose_.x - last_pose_.x) / interval, (pose_.y - last_pose_.y) / interval,
              (pose_.tilt - last_pose_.tilt) / interval, static_cast<double>(t_) / m.steps});
    return o;
  }
  void step(std::span<const double> action) override {
    if (done()) return;
    const int cs = env_.flip_config().control_steps;
    PanPose next = pose_;
    next.x += std::clamp(action[0], -1.0, 1.0) * step_scale_[0];
    next.y += std::clamp(action[1], -1.0, 1.0) * step_scale_[1];
    next.tilt += std::clamp(action[2], -1.0, 1.0) * step_scale_[2];
    // rows t+1 .. t+cs of the path: the chord from pose_ to next
    for (int s = 1; s <= cs; ++s) pan_->set_pose(t_ + s, lerp(pose_, next, static_cast<double>(s) / cs));
    const ClothInputs in{env_.model().stiffness, {}};
    for (int s = 0; s < cs; ++s) cloth_step(cloth_, in, t_ + s, state_, force_);
    t_ += cs;
    last_pose_ = pose_;
    pose_ = next;
    if (!finite_state(state_)) blown_up_ = true;
  }
  bool done() const override { return t_ >= env_.model().steps || blown_up_; }
  double final_loss() const override {
    if (blown_up_) return std::numeric_limits<double>::quiet_NaN();
    return env_.final_loss(state_, pose_);
  }

 private:
  const FlipEnv& env_;
  std::shared_ptr<PanSurface> pan_;
  ClothModel cloth_;
  std::array<double, 3> step_scale_;
  ClothState state_;
  std::vector<Vec3> force_;
  PanPose pose_, last_pose_;
  int t_ = 0;
  bool blown_up_ = false;
};

}  // namespace

ClothModel cloth_with_pan(const FlipModel& m, const std::shared_ptr<PanSurface>& pan) {
  ClothModel c = m.cloth;
  c.surfaces.insert(c.surfaces.begin(), pan);
  return c;
}

FlipEnv::FlipEnv(std::string name, FlipConfig cfg)
    : ConfigModelEnv(flip_info(std::move(name), cfg), cfg, build_flip_model) {}

nlohmann::json FlipEnv::config() const {
  nlohmann::json j = cfg_.to_json();
  j["params"] =
      "5 waypoints x (pan x, pan y, tilt) = x * half_range, linearly interpolated over segment_time each from the "
      "start pose (0, 0, 0), then held for settle_time";
  j["loss"] =
      "mean over the 4 corners of |final x - target|, target = start corner mirrored x -> -x in the pan frame, on the "
      "bottom, posed by waypoint 5";
  j["rl"] = "action every control_steps steps: pose increment a * 2 half_range control_steps / segment_steps";
  return j;
}

std::unique_ptr<Workspace> FlipEnv::make_workspace() const {
  const FlipModel& m = model();
  auto ws = std::make_unique<FlipWorkspace>();
  ws->pan = std::make_shared<PanSurface>(cfg_.pan);
  ws->cloth = cloth_with_pan(m, ws->pan);
  const int n = m.cloth.vertices();
  ws->path.resize(std::size_t(m.steps) + 1);
  ws->tape.reset(n, static_cast<int>(m.cloth.springs.size()), m.steps);
  ws->force.resize(n);
  ws->final_bar.reset(n);
  return ws;
}

std::unique_ptr<RlEnv> FlipEnv::make_rl() const { return std::make_unique<FlipRl>(*this); }

std::array<PanPose, 6> FlipEnv::waypoints(std::span<const double> x) const {
  std::array<PanPose, 6> w{};
  for (int k = 1; k <= kWaypoints; ++k) {
    const double* p = x.data() + 3 * (k - 1);
    w[k] = {p[0] * cfg_.half_range[0], p[1] * cfg_.half_range[1], p[2] * cfg_.half_range[2]};
  }
  return w;
}

void FlipEnv::fill_path(std::span<const double> x, std::vector<PanPose>& path) const {
  const FlipModel& m = model();
  const auto w = waypoints(x);
  const int per = m.segment_steps;
  path.resize(std::size_t(m.steps) + 1);
  // pose(t) = W_k + alpha (W_{k+1} - W_k), k = t / per, alpha = (t - k per) / per; W_5 after
  for (int t = 0; t <= m.steps; ++t) {
    const int k = t / per;
    path[t] = k >= kWaypoints ? w[kWaypoints] : lerp(w[k], w[k + 1], static_cast<double>(t - k * per) / per);
  }
}

std::vector<PanPose> FlipEnv::pose_path(std::span<const double> x) const {
  std::vector<PanPose> p;
  fill_path(x, p);
  return p;
}

std::array<double, 3> FlipEnv::max_step() const {
  const double f = 2.0 * cfg_.control_steps / cfg_.segment_steps();
  return {f * cfg_.half_range[0], f * cfg_.half_range[1], f * cfg_.half_range[2]};
}

std::vector<double> FlipEnv::rl_actions(std::span<const double> x) const {
  // segment k spans segment_steps / control_steps intervals of (W_{k+1} - W_k) / intervals each;
  // then zeros while the pan holds W_5
  const FlipModel& m = model();
  const auto w = waypoints(x);
  const int per_segment = m.segment_steps / cfg_.control_steps;
  const int horizon = m.steps / cfg_.control_steps;
  const auto scale = max_step();
  std::vector<double> a(std::size_t(horizon) * 3, 0.0);
  for (int j = 0; j < kWaypoints * per_segment && j < horizon; ++j) {
    const int k = j / per_segment;
    const double d[3] = {w[k + 1].x - w[k].x, w[k + 1].y - w[k].y, w[k + 1].tilt - w[k].tilt};
    for (int c = 0; c < 3; ++c) a[std::size_t(j) * 3 + c] = scale[c] > 0.0 ? d[c] / per_segment / scale[c] : 0.0;
  }
  return a;
}

std::array<Vec3, 4> FlipEnv::corner_targets(const PanPose& final_pose) const {
  const FlipModel& m = model();
  std::array<Vec3, 4> t;
  for (int k = 0; k < 4; ++k) t[k] = PanSurface::to_world(final_pose, m.corner_target_local[k]);
  return t;
}

double FlipEnv::final_loss(const ClothState& s, const PanPose& final_pose) const {
  if (!finite_state(s)) return std::numeric_limits<double>::quiet_NaN();
  const FlipModel& m = model();
  const auto target = corner_targets(final_pose);
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) sum += (s.x[m.corners[k]] - target[k]).norm();
  return sum / 4.0;
}

double FlipEnv::orientation(const ClothState& s, const PanPose& pan) const {
  const FlipModel& m = model();
  const Vec3& x0 = s.x[m.corners[0]];
  const Vec3 nrm = (s.x[m.corners[2]] - x0).cross(s.x[m.corners[1]] - x0);
  const double l = nrm.norm();
  // the pan's axis R(tilt) e_y = (-sin, cos, 0)
  const Vec3 axis = PanSurface::to_world(PanPose{0.0, 0.0, pan.tilt}, Vec3::UnitY());
  return l > 0.0 ? nrm.dot(axis) / l : 0.0;
}

ClothState FlipEnv::final_state(std::span<const double> x) const {
  auto ws = make_workspace();
  auto& w = static_cast<FlipWorkspace&>(*ws);
  (void)rollout(x, w, serial_team());
  return w.state;
}

std::unique_ptr<Workspace> FlipEnv::taped_rollout(std::span<const double> x) const {
  const FlipModel& m = model();
  auto base = make_workspace();
  auto& ws = static_cast<FlipWorkspace&>(*base);
  fill_path(x, ws.path);
  ws.pan->set_path(ws.path, ws.cloth.dt);
  cloth_rollout(ws.cloth, ClothInputs{m.stiffness, {}}, rest_state(ws.cloth), m.steps, ws.tape);
  return base;
}

std::vector<char> FlipEnv::contact_pattern(std::span<const double> x) const {
  const FlipModel& m = model();
  const auto base = taped_rollout(x);
  const auto& ws = static_cast<const FlipWorkspace&>(*base);
  const int n = ws.cloth.vertices();
  // the surfaces that acted on each vertex in each step, as cloth_step recorded them
  std::vector<char> flags(std::size_t(m.steps) * n, 0);
  for (int t = 0; t < m.steps; ++t) {
    const auto acted = ws.tape.contact(t);
    std::copy(acted.begin(), acted.end(), flags.begin() + std::size_t(t) * n);
  }
  return flags;
}

double FlipEnv::rollout(std::span<const double> x, Workspace& workspace, ThreadTeam&) const {
  auto& ws = static_cast<FlipWorkspace&>(workspace);
  const FlipModel& m = model();
  fill_path(x, ws.path);
  ws.pan->set_path(ws.path, ws.cloth.dt);
  ws.state = rest_state(ws.cloth);
  ws.force.resize(ws.cloth.vertices());
  const ClothInputs in{m.stiffness, {}};
  for (int t = 0; t < m.steps; ++t) cloth_step(ws.cloth, in, t, ws.state, ws.force);
  return final_loss(ws.state, ws.path.back());
}

double FlipEnv::rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& workspace,
                                  ThreadTeam&) const {
  auto& ws = static_cast<FlipWorkspace&>(workspace);
  const FlipModel& m = model();
  const int n = ws.cloth.vertices();
  fill_path(x, ws.path);
  ws.pan->set_path(ws.path, ws.cloth.dt);
  const ClothInputs in{m.stiffness, {}};
  // forward pass on the tape (the same steps as rollout())
  ws.state = cloth_rollout(ws.cloth, in, rest_state(ws.cloth), m.steps, ws.tape);
  const PanPose& last = ws.path.back();
  const double loss = final_loss(ws.state, last);
  if (!std::isfinite(loss)) {
    std::fill(grad.begin(), grad.end(), std::numeric_limits<double>::quiet_NaN());
    return loss;
  }
  // dLoss/d(final corner positions) and d/d(final pose) through the targets
  const auto target = corner_targets(last);
  ws.final_bar.reset(n);
  double s = 0.0, c = 1.0;
  dm::sincos(last.tilt, &s, &c);
  double w5_bar[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < 4; ++k) {
    const Vec3 u = 0.25 * unit_or_zero(ws.state.x[m.corners[k]] - target[k]);
    ws.final_bar.x[m.corners[k]] = u;
    // target = c + R(theta) l: d/dc = I, d/dtheta = R' l
    const Vec3& l = m.corner_target_local[k];
    const Vec3 dR_l(-s * l.x() - c * l.y(), c * l.x() - s * l.y(), 0.0);
    w5_bar[0] -= u.x();
    w5_bar[1] -= u.y();
    w5_bar[2] -= u.dot(dR_l);
  }
  // reverse pass through every step
  cloth_rollout_adjoint(ws.cloth, in, ws.tape, ws.final_bar, nullptr, ws.grad);
  const std::vector<double>& path_bar = ws.grad.surface_params[0];  // the pan: 3 (steps + 1)
  // the interpolation's reverse: pose(t) = (1 - alpha) W_k + alpha W_{k+1}
  double wbar[kWaypoints + 1][3] = {};
  const int per = m.segment_steps;
  for (int t = 0; t <= m.steps; ++t) {
    const int k = t / per;
    const double* pb = path_bar.data() + 3 * std::size_t(t);
    if (k >= kWaypoints) {
      for (int j = 0; j < 3; ++j) wbar[kWaypoints][j] += pb[j];
      continue;
    }
    const double alpha = static_cast<double>(t - k * per) / per;
    for (int j = 0; j < 3; ++j) {
      wbar[k][j] += (1.0 - alpha) * pb[j];
      wbar[k + 1][j] += alpha * pb[j];
    }
  }
  for (int j = 0; j < 3; ++j) wbar[kWaypoints][j] += w5_bar[j];
  // W_k = x * half_range (waypoint 0 is fixed)
  for (int k = 1; k <= kWaypoints; ++k)
    for (int j = 0; j < 3; ++j) grad[3 * (k - 1) + j] = wbar[k][j] * cfg_.half_range[j];
  return loss;
}

EnvFamily flip_family() {
  return single_env_family(
      "flip",
      "14 x 14 cm mass-spring pancake (9 x 9) in a round pan (radius 20 cm, cubic rim); 5 waypoints x (pan x, y, "
      "tilt), 0.12 s each, then 0.4 s settling (dt 1e-3); loss: corners to their flipped-over positions in the pan",
      [] { return std::make_unique<FlipEnv>("flip", FlipConfig{}); });
}

}  // namespace dsb::cloth
