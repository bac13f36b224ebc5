#include "envs/rigid/pinball_env.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/det_math.hpp"
#include "envs/rigid/contact.hpp"

namespace dsb {

PinballModel PinballModel::build(const PinballConfig& cfg) {
  cfg.validate();
  PinballModel m;
  static_cast<BallConstants&>(m) =
      BallConstants::of(cfg.dt, cfg.duration, cfg.ball_mass, cfg.ball_radius, cfg.gravity, cfg.contact);
  m.width = cfg.width;
  m.half_segment = 0.5 * (cfg.paddle_length - cfg.paddle_thickness);
  m.paddle_radius = 0.5 * cfg.paddle_thickness;
  // bounding circle of a paddle grown by the ball radius; the relative margin covers rounding, so
  // skipping a paddle beyond it never drops a contact
  m.reach = (m.half_segment + m.paddle_radius + m.radius) * (1.0 + 1e-9);
  m.paddles = cfg.rows * cfg.cols;
  for (int r = 0; r < cfg.rows; ++r)
    for (int c = 0; c < cfg.cols; ++c) {
      const auto p = cfg.paddle_centre(r, c);
      m.centres.emplace_back(p[0], p[1]);
    }
  return m;
}

namespace {

// rotation by +90 degrees: J (a, b) = (-b, a)
Eigen::Vector2d perp(const Eigen::Vector2d& a) { return Eigen::Vector2d(-a.y(), a.x()); }

}  // namespace

void pinball_step(const PinballModel& m, const PaddleAxes& axes, Ball2State& s, PinballStepCache* cache,
                  PaddleContactGrad* contacts) {
  const Eigen::Vector2d& p = s.position;
  const Eigen::Vector2d& v = s.velocity;
  Eigen::Vector2d f = Eigen::Vector2d::Zero();
  Eigen::Matrix2d df_dx = Eigen::Matrix2d::Zero(), df_dv = Eigen::Matrix2d::Zero();
  int walls = 0, n_paddle = 0;
  auto add = [&](const ContactForce<2>& c) {
    f += c.f;
    df_dx += c.df_dx;
    df_dv += c.df_dv;
  };
  // walls and floor: planes x = 0 (normal +x), x = width (normal -x), y = 0 (normal +y)
  const ContactGeometry<2> planes[3] = {plane_geometry<2>(p, Eigen::Vector2d::UnitX(), 0.0),
                                        plane_geometry<2>(p, -Eigen::Vector2d::UnitX(), -m.width),
                                        plane_geometry<2>(p, Eigen::Vector2d::UnitY(), 0.0)};
  for (int i = 0; i < 3; ++i) {
    const ContactForce<2> c = contact_force<2>(m.contact, m.radius, planes[i], v);
    if (!c.active) continue;
    add(c);
    walls |= 1 << i;
  }
  // paddles: capsules, skipped (exactly) when the ball is beyond their bounding circle
  const double reach2 = m.reach * m.reach;
  for (int k = 0; k < m.paddles; ++k) {
    const Eigen::Vector2d rel = p - m.centres[k];
    if (rel.squaredNorm() > reach2) continue;
    const ContactForce<2> c = contact_force<2>(
        m.contact, m.radius, capsule_geometry(p, m.centres[k], axes.axis[k], m.half_segment, m.paddle_radius), v);
    if (!c.active) continue;
    add(c);
    if (contacts) {
      // turning the paddle by da about its centre = turning the ball by -da about it, so
      // df/da = J f - (df/dx) J (p - centre) - (df/dv) J v
      contacts[n_paddle].paddle = k;
      contacts[n_paddle].df_dangle = perp(c.f) - c.df_dx * perp(rel) - c.df_dv * perp(v);
    }
    ++n_paddle;
  }
  if (cache) {
    cache->df_dx = df_dx;
    cache->df_dv = df_dv;
    cache->walls = walls;
    cache->paddle_contacts = contacts ? n_paddle : 0;
  }
  // semi-implicit Euler: v += dt (g + f / m); x += dt v
  const Eigen::Vector2d accel(f.x() / m.mass, f.y() / m.mass - m.gravity);
  s.velocity += m.dt * accel;
  s.position += m.dt * s.velocity;
}

void pinball_step_adjoint(const PinballModel& m, const PinballStepCache& cache, const PaddleContactGrad* contacts,
                          Ball2State& adj, double* angle_bar) {
  // x' = x + dt v': dL/dv' gains dt dL/dx'
  const Eigen::Vector2d vbar = adj.velocity + m.dt * adj.position;
  // v' = v + dt (g + f(x, v, angles) / m): dL/dx += dt/m (df/dx)^T vbar,
  // dL/dv = vbar + dt/m (df/dv)^T vbar, dL/da_k += dt/m (df/da_k) . vbar
  const double k = m.dt / m.mass;
  adj.position += k * (cache.df_dx.transpose() * vbar);
  adj.velocity = vbar + k * (cache.df_dv.transpose() * vbar);
  for (int i = 0; i < cache.paddle_contacts; ++i) angle_bar[contacts[i].paddle] += k * contacts[i].df_dangle.dot(vbar);
}

namespace {

EnvInfo pinball_info(std::string name, const PinballConfig& cfg) {
  cfg.validate();  // at construction, although the model is built on first use
  EnvInfo info;
  info.name = std::move(name);
  info.dim = cfg.rows * cfg.cols;
  info.differentiable = true;
  // `harness calibrate` on the 2-core EPYC (binary f21b88f): 86-123 us a gradient episode (1,920
  // steps against 2 to 16 paddles), 67-94 us a forward one
  info.cost_hint_s = 1.0e-4;
  info.smoothness = Smoothness::piecewise;  // paddle and wall contacts
  info.cost_hint_forward_s = 8e-5;
  return info;
}

}  // namespace

PinballEnv::PinballEnv(std::string name, PinballConfig cfg)
    : ConfigModelEnv(pinball_info(std::move(name), cfg), cfg, PinballModel::build) {}

std::unique_ptr<Workspace> PinballEnv::make_workspace() const {
  auto ws = std::make_unique<PinballWorkspace>();
  ws->caches.resize(model().steps);
  ws->contacts.reserve(model().steps);
  return ws;
}

std::vector<double> PinballEnv::paddle_angles(std::span<const double> x) const {
  const PinballModel& m = model();
  std::vector<double> a(m.paddles);
  for (int k = 0; k < m.paddles; ++k) a[k] = cfg_.max_angle * x[k];
  return a;
}

PaddleAxes PinballEnv::axes(std::span<const double> x) const {
  const PinballModel& m = model();
  PaddleAxes ax;
  for (int k = 0; k < m.paddles; ++k) {
    const double a = cfg_.max_angle * x[k];
    ax.axis[k] = Eigen::Vector2d(dm::cos(a), dm::sin(a));
  }
  return ax;
}

Ball2State PinballEnv::initial_state() const {
  Ball2State s;
  s.position = Eigen::Vector2d(cfg_.start[0], cfg_.start[1]);
  s.velocity.setZero();  // dropped at rest
  return s;
}

double PinballEnv::final_loss(const Ball2State& s) const {
  if (!s.position.allFinite() || !s.velocity.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  return (s.position - Eigen::Vector2d(cfg_.target[0], cfg_.target[1])).norm();
}

std::vector<Ball2State> PinballEnv::trajectory(std::span<const double> x) const {
  const PinballModel& m = model();
  const PaddleAxes ax = axes(x);
  std::vector<Ball2State> states;
  states.reserve(m.steps + 1);
  states.push_back(initial_state());
  for (int t = 0; t < m.steps; ++t) {
    Ball2State s = states.back();
    pinball_step(m, ax, s);
    states.push_back(s);
  }
  return states;
}

PinballContactSteps PinballEnv::contact_steps(std::span<const double> x) const {
  const PinballModel& m = model();
  const PaddleAxes ax = axes(x);
  PinballContactSteps n;
  n.paddles.assign(m.paddles, 0);
  Ball2State s = initial_state();
  PinballStepCache cache;
  std::array<PaddleContactGrad, kMaxPaddles> buf;
  for (int t = 0; t < m.steps; ++t) {
    pinball_step(m, ax, s, &cache, buf.data());
    n.left_wall += (cache.walls & 1) != 0;
    n.right_wall += (cache.walls & 2) != 0;
    n.floor += (cache.walls & 4) != 0;
    for (int i = 0; i < cache.paddle_contacts; ++i) ++n.paddles[buf[i].paddle];
  }
  return n;
}

double PinballEnv::rollout(std::span<const double> x, Workspace&, ThreadTeam&) const {
  const PinballModel& m = model();
  const PaddleAxes ax = axes(x);
  Ball2State s = initial_state();
  for (int t = 0; t < m.steps; ++t) pinball_step(m, ax, s);
  return final_loss(s);
}

double PinballEnv::rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& workspace,
                                     ThreadTeam&) const {
  const PinballModel& m = model();
  auto& ws = static_cast<PinballWorkspace&>(workspace);
  const PaddleAxes ax = axes(x);
  // forward pass: per-step caches, and the active paddle contacts of all steps in one list
  std::vector<PinballStepCache>& caches = ws.caches;
  std::vector<PaddleContactGrad>& contacts = ws.contacts;
  contacts.clear();
  std::array<PaddleContactGrad, kMaxPaddles> buf;
  Ball2State s = initial_state();
  for (int t = 0; t < m.steps; ++t) {
    pinball_step(m, ax, s, &caches[t], buf.data());
    contacts.insert(contacts.end(), buf.begin(), buf.begin() + caches[t].paddle_contacts);
  }
  const double loss = final_loss(s);
  if (!std::isfinite(loss)) {
    std::fill(grad.begin(), grad.end(), std::numeric_limits<double>::quiet_NaN());
    return loss;
  }
  // dLoss/d(final state): loss = |x_N - target| (zero direction at a zero distance)
  Ball2State adj;
  const Eigen::Vector2d d = s.position - Eigen::Vector2d(cfg_.target[0], cfg_.target[1]);
  adj.position = loss > 0.0 ? Eigen::Vector2d(d / loss) : Eigen::Vector2d::Zero();
  adj.velocity.setZero();
  // reverse pass through the steps; each step's contacts end where the next step's begin
  std::array<double, kMaxPaddles> angle_bar{};
  std::size_t end = contacts.size();
  for (int t = m.steps - 1; t >= 0; --t) {
    const std::size_t begin = end - caches[t].paddle_contacts;
    pinball_step_adjoint(m, caches[t], contacts.data() + begin, adj, angle_bar.data());
    end = begin;
  }
  // chain rule through angle = max_angle x
  for (int k = 0; k < m.paddles; ++k) grad[k] = cfg_.max_angle * angle_bar[k];
  return loss;
}

EnvFamily pinball_family(int rows, int cols) {
  const std::string name = "pinball-" + std::to_string(rows) + "x" + std::to_string(cols);
  EnvFamily f;
  f.pattern = name;
  f.description = "ball dropped through a " + std::to_string(rows) + " x " + std::to_string(cols) +
      " grid of paddles on an 8 x 10 m board (penalty contact, dt 1/480, 4 s), " + std::to_string(rows * cols) +
      "-D paddle angles, target (7, 0.5)";
  f.grid_names = {name};
  f.try_make = [name, rows, cols](const std::string& requested) -> std::unique_ptr<Env> {
    if (requested != name) return nullptr;
    return std::make_unique<PinballEnv>(name, PinballConfig::grid(rows, cols));
  };
  return f;
}

}  // namespace dsb
