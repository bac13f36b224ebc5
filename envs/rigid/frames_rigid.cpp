// Scenes of the rigid envs for `harness render` (Env::frames): each env's own trajectory(), the
// same steps as its loss path, cut at the frame steps. Side view for the 2-D cartpoles and
// pinball, oblique for bounce.
#include <algorithm>
#include <cmath>

#include "common/det_math.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_env.hpp"
#include "envs/rigid/pinball_env.hpp"

namespace dsb {

namespace {

ScenePoint p2(double x, double y) { return {x, y, 0.0}; }
ScenePoint p3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// axis-aligned rectangle in the x-y plane, closed polyline
Polyline rectangle(Role role, std::string name, double x0, double y0, double x1, double y1) {
  return {role, std::move(name), {p2(x0, y0), p2(x1, y0), p2(x1, y1), p2(x0, y1)}, true};
}

}  // namespace

std::vector<Frame> CartpoleEnv::frames(std::span<const double> x, int n, ThreadTeam&) const {
  const CartpoleModel& m = model();
  const std::vector<CartpoleState> states = trajectory(x);  // (steps + 1)
  // the rail spans every cart position of the episode, plus a margin
  double lo = 0.0, hi = 0.0;
  for (const auto& s : states) {
    lo = std::min(lo, s.x);
    hi = std::max(hi, s.x);
  }
  const double reach = m.n * m.length;
  std::vector<Frame> out;
  for (const int step : frame_steps(cfg_.steps, n)) {
    const CartpoleState& s = states[step];
    Frame f{step, step * cfg_.dt, {}};
    Scene& sc = f.scene;
    sc.camera = Camera::side;
    // rail, cart (0.4 x 0.2 m around its position)
    sc.lines.push_back({Role::fixed, "rail", {p2(lo - 0.5 * reach, 0.0), p2(hi + 0.5 * reach, 0.0)}});
    sc.lines.push_back(rectangle(Role::tool, "cart", s.x - 0.2, -0.1, s.x + 0.2, 0.1));
    // links: the joints from the cart to the tip, (links + 1) points
    Polyline links{Role::state, "links", {p2(s.x, 0.0)}};
    double jx = s.x, jy = 0.0;
    for (int i = 0; i < m.n; ++i) {
      jx += m.length * dm::sin(s.phi(i));
      jy -= m.length * dm::cos(s.phi(i));
      links.points.push_back(p2(jx, jy));
    }
    sc.lines.push_back(links);
    // the tip's path up to this step
    Polyline trace{Role::trace, "tip trace", {}};
    for (int t = 0; t <= step; ++t) {
      const Eigen::Vector2d tip = cartpole_tip(m, states[t]);
      trace.points.push_back(p2(tip.x(), tip.y()));
    }
    if (trace.points.size() >= 2) sc.lines.push_back(trace);
    const Eigen::Vector2d tip = cartpole_tip(m, s);
    sc.discs.push_back({Role::target, "target", p2(cfg_.target[0], cfg_.target[1]), 0.08, false});
    sc.discs.push_back({Role::state, "tip", p2(tip.x(), tip.y()), 0.05, true});
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<Frame> BounceEnv::frames(std::span<const double> x, int n, ThreadTeam&) const {
  const BounceModel& m = model();
  const std::vector<BallState> states = trajectory(x);  // (steps + 1)
  // ground patch: every ball position and the target, with a margin, up to the wall
  const Eigen::Vector3d target(cfg_.target[0], cfg_.target[1], cfg_.target[2]);
  Eigen::Vector3d lo = target, hi = target;
  for (const auto& s : states)
    if (s.position.allFinite()) {
      lo = lo.cwiseMin(s.position);
      hi = hi.cwiseMax(s.position);
    }
  const double x0 = lo.x() - 0.5, x1 = m.wall_x, z0 = lo.z() - 0.5, z1 = hi.z() + 0.5;
  const double top = std::max(hi.y(), 1.0) + 0.25;
  std::vector<Frame> out;
  for (const int step : frame_steps(m.steps, n)) {
    Frame f{step, step * m.dt, {}};
    Scene& sc = f.scene;
    sc.camera = Camera::oblique;
    sc.lines.push_back({Role::fixed, "ground", {{x0, 0, z0}, {x1, 0, z0}, {x1, 0, z1}, {x0, 0, z1}}, true});
    sc.lines.push_back({Role::fixed, "wall", {{x1, 0, z0}, {x1, top, z0}, {x1, top, z1}, {x1, 0, z1}}, true});
    Polyline trace{Role::trace, "ball trace", {}};
    for (int t = 0; t <= step; ++t) trace.points.push_back(p3(states[t].position));
    if (trace.points.size() >= 2) sc.lines.push_back(trace);
    // the ball's shadow on the ground helps read depth
    const Eigen::Vector3d& b = states[step].position;
    sc.discs.push_back({Role::fixed, "shadow", {b.x(), 0.0, b.z()}, m.radius, false});
    sc.discs.push_back({Role::target, "target", p3(target), 0.08, false});
    sc.discs.push_back({Role::state, "ball", p3(b), m.radius, true});
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<Frame> PinballEnv::frames(std::span<const double> x, int n, ThreadTeam&) const {
  const PinballModel& m = model();
  const std::vector<Ball2State> states = trajectory(x);  // (steps + 1)
  const std::vector<double> angles = paddle_angles(x);
  std::vector<Frame> out;
  for (const int step : frame_steps(m.steps, n)) {
    Frame f{step, step * m.dt, {}};
    Scene& sc = f.scene;
    sc.camera = Camera::side;
    sc.lines.push_back(
        {Role::fixed, "board", {p2(0, cfg_.height), p2(0, 0), p2(m.width, 0), p2(m.width, cfg_.height)}});
    // paddles: the capsule's box outline at its angle (paddle_length x paddle_thickness)
    for (int k = 0; k < m.paddles; ++k) {
      const Eigen::Vector2d a(dm::cos(angles[k]), dm::sin(angles[k])), nrm(-a.y(), a.x());
      const Eigen::Vector2d c = m.centres[k];
      const double h = 0.5 * cfg_.paddle_length, r = m.paddle_radius;
      Polyline box{Role::tool, "paddle " + std::to_string(k), {}, true};
      for (const auto& [sa, sn] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
        const Eigen::Vector2d q = c + sa * h * a + sn * r * nrm;
        box.points.push_back(p2(q.x(), q.y()));
      }
      sc.lines.push_back(box);
    }
    Polyline trace{Role::trace, "ball trace", {}};
    for (int t = 0; t <= step; ++t) trace.points.push_back(p2(states[t].position.x(), states[t].position.y()));
    if (trace.points.size() >= 2) sc.lines.push_back(trace);
    const Eigen::Vector2d& b = states[step].position;
    sc.discs.push_back({Role::target, "target", p2(cfg_.target[0], cfg_.target[1]), 0.25, false});
    sc.discs.push_back({Role::state, "ball", p2(b.x(), b.y()), m.radius, true});
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace dsb
