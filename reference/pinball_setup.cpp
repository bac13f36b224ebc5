// The cross-check's setup of `pinball-RxC`: a ball dropped through paddles at the parameters'
// angles; free flight, first impact and first rebound compared (after a few paddle hits the
// paths are chaotic: final positions and bounce counts are reported only).
#include <cmath>
#include <memory>

#include "envs/rigid/contact.hpp"
#include "envs/rigid/pinball_env.hpp"
#include "reference/bullet_adapter.hpp"
#include "reference/mujoco_adapter.hpp"
#include "reference/setup.hpp"

namespace dsb::reference {
namespace {

Rollout ball_rollout(const std::string& engine, const std::vector<Ball2State>& states, double loss) {
  Rollout r;
  r.engine = engine;
  for (const auto& s : states) {
    r.position.push_back(lift(s.position));
    r.velocity.push_back(lift(s.velocity));
  }
  r.final_loss = loss;
  return r;
}

class PinballSetup : public RigidSetup<PinballEnv> {
 public:
  PinballSetup(const std::string& name, PinballConfig cfg) : RigidSetup(name, name, std::move(cfg)) {}
  bool contact() const override { return true; }

  std::vector<std::vector<double>> vectors(Rng& rng) const override {
    // paddle angles over the whole range
    return uniform_vectors(rng, 12, env_.dim(), -1.0, 1.0);
  }

  Tolerances tolerances(const std::string&) const override { return ball_setup_tolerances(); }

  Rollout ours(std::span<const double> x) const override {
    const auto states = env_.trajectory(x);
    return ball_rollout("ours", states, env_.final_loss(states.back()));
  }

  // the engines' paddles are static geometry: a model per parameter vector
  Rollout mujoco(std::span<const double> x) override {
    MujocoPinball sim(env_.pinball_config(), env_.paddle_angles(x));
    const auto states = sim.trajectory();
    return ball_rollout("mujoco", states, env_.final_loss(states.back()));
  }

  Rollout bullet(std::span<const double> x) override {
    BulletPinball sim(env_.pinball_config(), env_.paddle_angles(x));
    const auto states = sim.trajectory();
    return ball_rollout("bullet", states, env_.final_loss(states.back()));
  }

  Surface nearest_surface(std::span<const double> x, const Eigen::Vector3d& p) const override {
    // the signed distance of the centre to each surface and its outward normal
    const PinballModel& m = env_.model();
    const int cols = env_.pinball_config().cols;
    NearestSurface s;
    s.consider("floor", p.y(), Eigen::Vector3d::UnitY());
    s.consider("left wall", p.x(), Eigen::Vector3d::UnitX());
    s.consider("right wall", m.width - p.x(), -Eigen::Vector3d::UnitX());
    const auto angles = env_.paddle_angles(x);
    for (int k = 0; k < m.paddles; ++k) {
      const Eigen::Vector2d axis(std::cos(angles[k]), std::sin(angles[k]));
      const auto g = capsule_geometry(p.head<2>(), m.centres[k], axis, m.half_segment, m.paddle_radius);
      // a flat face when the closest point of the segment is inside it, else a rounded end
      const bool face = std::abs((p.head<2>() - m.centres[k]).dot(axis)) < m.half_segment;
      s.consider("paddle " + std::to_string(k / cols) + "," + std::to_string(k % cols), g.distance, lift(g.normal),
                 face);
    }
    return s.nearest();
  }
};

}  // namespace

SetupEntry pinball_setup(int rows, int cols) {
  const std::string name = "pinball-" + std::to_string(rows) + "x" + std::to_string(cols);
  return {name, [name, rows, cols]() -> std::unique_ptr<CrosscheckSetup> {
            return std::make_unique<PinballSetup>(name, PinballConfig::grid(rows, cols));
          }};
}

}  // namespace dsb::reference
