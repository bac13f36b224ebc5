// The cross-check's setup of `bounce`: a ball thrown against the ground and a wall; free flight,
// first impact, first rebound and ground bounces compared, final positions against Bullet.
#include <algorithm>
#include <memory>
#include <optional>

#include "envs/rigid/bounce_env.hpp"
#include "reference/bullet_adapter.hpp"
#include "reference/mujoco_adapter.hpp"
#include "reference/setup.hpp"

namespace dsb::reference {

bool bounce_throw_is_clear(const BounceConfig& cfg, std::span<const double> x) {
  // our own rollout, a quarter longer than the episode
  BounceConfig longer = cfg;
  longer.duration = 1.25 * cfg.duration;
  const BounceEnv env(longer);
  Rollout r;
  for (const auto& s : env.trajectory(x)) {
    r.position.push_back(s.position);
    r.velocity.push_back(s.velocity);
  }
  const ContactEvents e = contact_events(r, Eigen::Vector3d(0.0, -env.model().gravity, 0.0), env.model().dt);
  const int horizon = BounceModel::build(cfg).steps;
  if (e.clearest_graze < 2.0) return false;
  for (int start : e.episode_starts) {
    if (start >= static_cast<int>(0.85 * horizon)) return false;
    // one surface at a time: the other one at least 0.3 m beyond the contact radius (a bounce
    // into the corner is one episode in a soft model and two in an impulse one)
    const Eigen::Vector3d& p = r.position[start];
    if (std::max(p.y(), cfg.wall_x - p.x()) < cfg.radius + 0.3) return false;
  }
  return true;
}

namespace {

Rollout ball_rollout(const std::string& engine, const std::vector<BallState>& states, double loss) {
  Rollout r;
  r.engine = engine;
  for (const auto& s : states) {
    r.position.push_back(s.position);
    r.velocity.push_back(s.velocity);
  }
  r.final_loss = loss;
  return r;
}

class BounceSetup : public RigidSetup<BounceEnv> {
 public:
  BounceSetup() : RigidSetup("bounce", BounceConfig{}) {}
  bool contact() const override { return true; }

  std::vector<std::vector<double>> vectors(Rng& rng) const override {
    // throws over the whole box, kept when they are clear (not grazing, no bounce at the end)
    std::vector<std::vector<double>> xs;
    while (xs.size() < 24) {
      std::vector<double> x(3);
      for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
      if (bounce_throw_is_clear(env_.bounce_config(), x)) xs.push_back(std::move(x));
    }
    return xs;
  }

  Tolerances tolerances(const std::string& engines) const override {
    Tolerances t = ball_setup_tolerances();
    // ground bounces: equal on every clear throw (374 of 374, all pairs)
    t.bounces = 0;
    // Bullet's friction is Coulomb's, like ours: final positions measured within 0.39 m; MuJoCo
    // 2.2's soft friction is weaker in impacts, so its final position is reported only
    if (engines == "ours-bullet") t.final_position = 0.75;
    return t;
  }

  Rollout ours(std::span<const double> x) const override {
    const auto states = env_.trajectory(x);
    return ball_rollout("ours", states, env_.final_loss(states.back()));
  }

  Rollout mujoco(std::span<const double> x) override {
    if (!mujoco_) mujoco_.emplace(env_.bounce_config());
    const auto states = mujoco_->trajectory(env_.initial_velocity(x));
    return ball_rollout("mujoco", states, env_.final_loss(states.back()));
  }

  Rollout bullet(std::span<const double> x) override {
    if (!bullet_) bullet_ = std::make_unique<BulletBounce>(env_.bounce_config());
    const auto states = bullet_->trajectory(env_.initial_velocity(x));
    return ball_rollout("bullet", states, env_.final_loss(states.back()));
  }

  Surface nearest_surface(std::span<const double>, const Eigen::Vector3d& p) const override {
    // the signed distance of the centre to each surface and its outward normal
    NearestSurface s;
    s.consider("ground", p.y(), Eigen::Vector3d::UnitY());
    s.consider("wall", env_.model().wall_x - p.x(), -Eigen::Vector3d::UnitX());
    return s.nearest();
  }

 private:
  std::optional<MujocoBounce> mujoco_;
  std::unique_ptr<BulletBounce> bullet_;
};

}  // namespace

SetupEntry bounce_setup() {
  return {"bounce", []() -> std::unique_ptr<CrosscheckSetup> { return std::make_unique<BounceSetup>(); }};
}

}  // namespace dsb::reference
