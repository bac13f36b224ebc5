#include "reference/engine_cartpole.hpp"

#include <stdexcept>

namespace dsb::reference {

std::vector<Eigen::Vector2d> EngineCartpole::tip_trajectory(const CartpoleEnv& env, std::span<const double> x) {
  if (env.cartpole_config().to_json() != cfg_.to_json())
    throw std::invalid_argument(model_ + ": env '" + env.name() + "' has another config");
  if (static_cast<int>(x.size()) != env.dim())
    throw std::invalid_argument(model_ + ": expected " + std::to_string(env.dim()) + " parameters, got " +
                                std::to_string(x.size()));
  reset();
  std::vector<Eigen::Vector2d> tips{tip()};
  tips.reserve(cfg_.steps + 1);
  for (int t = 0; t < cfg_.steps; ++t) {
    // the env's own parameter map
    const CartpoleControls c = env.controls(x, t);
    step(c.u, c.tau);
    tips.push_back(tip());
  }
  return tips;
}

CartpoleState EngineCartpole::state_from_joints(std::span<const double> q, std::span<const double> dq) const {
  CartpoleState s;
  s.x = q[0];
  s.vx = dq[0];
  s.phi = LinkVec::Zero(cfg_.links);
  s.dphi = LinkVec::Zero(cfg_.links);
  // absolute angles are running sums of the relative joint angles
  double phi = 0.0, dphi = 0.0;
  for (int i = 0; i < cfg_.links; ++i) {
    phi += q[1 + i];
    dphi += dq[1 + i];
    s.phi(i) = phi;
    s.dphi(i) = dphi;
  }
  return s;
}

}  // namespace dsb::reference
