// The cross-check's setup of `cartpole1` and `cartpole3`: no contact, the tip compared over the
// whole horizon and the final loss.
#include <cmath>
#include <limits>
#include <optional>

#include "envs/rigid/cartpole_env.hpp"
#include "reference/bullet_adapter.hpp"
#include "reference/mujoco_adapter.hpp"
#include "reference/setup.hpp"

namespace dsb::reference {
namespace {

// the cartpole loss of a tip: L2 to the target
double tip_loss(const CartpoleConfig& cfg, const Eigen::Vector3d& tip) {
  if (!tip.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  return std::hypot(tip.x() - cfg.target[0], tip.y() - cfg.target[1]);
}

Rollout tip_rollout(const std::string& engine, const std::vector<Eigen::Vector2d>& tips, const CartpoleConfig& cfg) {
  Rollout r;
  r.engine = engine;
  for (const auto& p : tips) r.position.push_back(lift(p));
  r.final_loss = tip_loss(cfg, r.position.back());
  return r;
}

class CartpoleSetup : public RigidSetup<CartpoleEnv> {
 public:
  CartpoleSetup(const std::string& name, CartpoleConfig cfg) : RigidSetup(name, name, std::move(cfg)) {}
  bool contact() const override { return false; }

  std::vector<std::vector<double>> vectors(Rng& rng) const override {
    // open-loop controls uniform in [-0.5, 0.5] (half the speed and torque bounds)
    return uniform_vectors(rng, 8, env_.dim(), -0.5, 0.5);
  }

  Tolerances tolerances(const std::string& engines) const override {
    // contact-free: the same semi-implicit recursion everywhere. 1e-6 is the requirement for
    // MuJoCo; Bullet, measured at 1.1e-13, gets 1e-9 (round-off growth on other builds)
    Tolerances t;
    t.deviation = engines == "ours-bullet" ? 1e-9 : 1e-6;
    t.loss = t.deviation;
    return t;
  }

  Rollout ours(std::span<const double> x) const override {
    Rollout r;
    r.engine = "ours";
    const auto states = env_.trajectory(x);
    for (const auto& s : states) r.position.push_back(lift(cartpole_tip(env_.model(), s)));
    r.final_loss = env_.final_loss(states.back());
    return r;
  }

  Rollout mujoco(std::span<const double> x) override {
    if (!mujoco_) mujoco_.emplace(env_.cartpole_config());
    return tip_rollout("mujoco", mujoco_->tip_trajectory(env_, x), env_.cartpole_config());
  }

  Rollout bullet(std::span<const double> x) override {
    if (!bullet_) bullet_ = std::make_unique<BulletCartpole>(env_.cartpole_config());
    return tip_rollout("bullet", bullet_->tip_trajectory(env_, x), env_.cartpole_config());
  }

 private:
  std::optional<MujocoCartpole> mujoco_;
  std::unique_ptr<BulletCartpole> bullet_;
};

}  // namespace

SetupEntry cartpole_setup(int links) {
  const std::string name = "cartpole" + std::to_string(links);
  return {name, [name, links]() -> std::unique_ptr<CrosscheckSetup> {
            return std::make_unique<CartpoleSetup>(
                name, links == 1 ? CartpoleConfig::one_link() : CartpoleConfig::three_links());
          }};
}

}  // namespace dsb::reference
