#include "envs/rigid/cartpole_env.hpp"

#include <cmath>
#include <limits>

#include "common/det_math.hpp"

namespace dsb {

namespace {

EnvInfo cartpole_info(std::string name, const CartpoleConfig& cfg) {
  cfg.validate();  // at construction, although the model is built on first use
  EnvInfo info;
  info.name = std::move(name);
  info.dim = cfg.steps * (1 + cfg.links);
  info.differentiable = true;
  info.rl = true;
  // `harness calibrate` on the 2-core EPYC (binary f21b88f): cartpole1 (1 link) 8.5 us forward,
  // 14 us gradient; cartpole3 21 us and 36 us; linear in the links in between
  info.cost_hint_forward_s = 2e-6 + 6.3e-6 * cfg.links;
  info.cost_hint_s = 3.5e-6 + 1.1e-5 * cfg.links;
  return info;
}

}  // namespace

CartpoleEnv::CartpoleEnv(std::string name, CartpoleConfig cfg)
    : ConfigModelEnv(cartpole_info(std::move(name), cfg), cfg, CartpoleModel::build) {}

std::unique_ptr<Workspace> CartpoleEnv::make_workspace() const {
  auto ws = std::make_unique<CartpoleWorkspace>();
  ws->states.resize(cfg_.steps + 1);
  ws->caches.resize(cfg_.steps);
  return ws;
}

namespace {

// physical controls of step t from the normalized parameters: u (m/s), tau (n, N m)
using StepControl = CartpoleControls;

StepControl control_at(const CartpoleConfig& cfg, std::span<const double> x, int t) {
  const int stride = 1 + cfg.links;
  StepControl c{};
  c.u = cfg.max_cart_speed * x[t * stride];
  for (int j = 0; j < cfg.links; ++j) c.tau[j] = cfg.max_torque * x[t * stride + 1 + j];
  return c;
}

bool finite_state(const CartpoleState& s) {
  return std::isfinite(s.x) && std::isfinite(s.vx) && s.phi.allFinite() && s.dphi.allFinite();
}

}  // namespace

CartpoleControls CartpoleEnv::controls(std::span<const double> x, int t) const { return control_at(cfg_, x, t); }

double CartpoleEnv::final_loss(const CartpoleState& s) const {
  if (!finite_state(s)) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector2d d = cartpole_tip(model(), s) - Eigen::Vector2d(cfg_.target[0], cfg_.target[1]);
  return d.norm();
}

std::vector<CartpoleState> CartpoleEnv::trajectory(std::span<const double> x) const {
  std::vector<CartpoleState> states;
  states.reserve(cfg_.steps + 1);
  states.push_back(cartpole_initial_state(model(), cfg_));
  for (int t = 0; t < cfg_.steps; ++t) {
    const StepControl c = control_at(cfg_, x, t);
    CartpoleState s = states.back();
    cartpole_step(model(), s, c.u, c.tau);
    states.push_back(s);
  }
  return states;
}

double CartpoleEnv::rollout(std::span<const double> x, Workspace&, ThreadTeam&) const {
  const CartpoleModel& m = model();
  CartpoleState s = cartpole_initial_state(m, cfg_);
  for (int t = 0; t < cfg_.steps; ++t) {
    const StepControl c = control_at(cfg_, x, t);
    cartpole_step(m, s, c.u, c.tau);
  }
  return final_loss(s);
}

double CartpoleEnv::rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& workspace,
                                      ThreadTeam&) const {
  const CartpoleModel& m = model();
  auto& ws = static_cast<CartpoleWorkspace&>(workspace);
  // forward pass, keeping the state before every step and what its reverse needs
  std::vector<CartpoleState>& states = ws.states;
  std::vector<CartpoleStepCache>& caches = ws.caches;
  states[0] = cartpole_initial_state(m, cfg_);
  for (int t = 0; t < cfg_.steps; ++t) {
    const StepControl c = control_at(cfg_, x, t);
    states[t + 1] = states[t];
    cartpole_step(m, states[t + 1], c.u, c.tau, &caches[t]);
  }
  const CartpoleState& last = states.back();
  const double loss = final_loss(last);
  if (!std::isfinite(loss)) {
    std::fill(grad.begin(), grad.end(), std::numeric_limits<double>::quiet_NaN());
    return loss;
  }
  // dLoss/d(final state): loss = |tip - target|, tip = (x + L sum sin phi, -L sum cos phi)
  const Eigen::Vector2d d = cartpole_tip(m, last) - Eigen::Vector2d(cfg_.target[0], cfg_.target[1]);
  const Eigen::Vector2d dir = loss > 0.0 ? Eigen::Vector2d(d / loss) : Eigen::Vector2d::Zero();
  CartpoleAdjoint adj;
  adj.x = dir.x();
  adj.vx = 0.0;
  adj.phi = LinkVec(m.n);
  adj.dphi = LinkVec::Zero(m.n);
  for (int i = 0; i < m.n; ++i)
    adj.phi(i) = m.length * (dir.x() * dm::cos(last.phi(i)) + dir.y() * dm::sin(last.phi(i)));

  // reverse pass through the steps; gradient in normalized units (chain rule through the scales)
  const int stride = 1 + cfg_.links;
  for (int t = cfg_.steps - 1; t >= 0; --t) {
    double u_bar = 0.0;
    double tau_bar[kMaxLinks];
    cartpole_step_adjoint(m, states[t], caches[t], adj, &u_bar, tau_bar);
    grad[t * stride] = cfg_.max_cart_speed * u_bar;
    for (int j = 0; j < cfg_.links; ++j) grad[t * stride + 1 + j] = cfg_.max_torque * tau_bar[j];
  }
  return loss;
}

namespace {

// Per-step interface: observation = (x, vx, phi_1..n, dphi_1..n), the joint positions and
// velocities as the paper's RL view (the state cartpole_step advances: Markov; no time), action =
// one step's normalized controls (cart speed, torques).
class CartpoleRl : public RlEnv {
 public:
  explicit CartpoleRl(const CartpoleEnv& env) : env_(env) { reset(); }
  int observation_dim() const override { return 2 + 2 * env_.model().n; }
  int action_dim() const override { return 1 + env_.model().n; }
  int horizon() const override { return env_.cartpole_config().steps; }
  // the seed: "in cartpole, as other methods take actions once per timestep, action repeat is 1"
  int action_repeat() const override { return 1; }
  void reset() override {
    state_ = cartpole_initial_state(env_.model(), env_.cartpole_config());
    t_ = 0;
  }
  std::vector<double> observe() const override {
    std::vector<double> o{state_.x, state_.vx};
    for (int i = 0; i < env_.model().n; ++i) o.push_back(state_.phi(i));
    for (int i = 0; i < env_.model().n; ++i) o.push_back(state_.dphi(i));
    return o;
  }
  void step(std::span<const double> action) override {
    if (done()) throw std::logic_error("cartpole: step after the episode ended");
    const auto& cfg = env_.cartpole_config();
    double tau[kMaxLinks];
    for (int j = 0; j < cfg.links; ++j) tau[j] = cfg.max_torque * clip(action[1 + j]);
    cartpole_step(env_.model(), state_, cfg.max_cart_speed * clip(action[0]), tau);
    ++t_;
  }
  bool done() const override { return t_ >= horizon(); }
  double final_loss() const override { return env_.final_loss(state_); }

 private:
  static double clip(double a) { return a < -1.0 ? -1.0 : (a > 1.0 ? 1.0 : a); }
  const CartpoleEnv& env_;
  CartpoleState state_;
  int t_ = 0;
};

}  // namespace

std::unique_ptr<RlEnv> CartpoleEnv::make_rl() const { return std::make_unique<CartpoleRl>(*this); }

EnvFamily cartpole_family(int links) {
  const std::string name = "cartpole" + std::to_string(links);
  EnvFamily f;
  f.pattern = name;
  f.description = links == 1
      ? "velocity-controlled cart + 1 link (1 kg), 100 steps, 200-D, tip target (1, 0.8)"
      : "velocity-controlled cart + 3 links (1, 0.5, 0.25 kg), 100 steps, 400-D, tip target (1, 2.5)";
  f.grid_names = {name};
  f.try_make = [name, links](const std::string& requested) -> std::unique_ptr<Env> {
    if (requested != name) return nullptr;
    return std::make_unique<CartpoleEnv>(name, links == 1 ? CartpoleConfig::one_link() : CartpoleConfig::three_links());
  };
  return f;
}

}  // namespace dsb
