#include <cstdio>
#include <iostream>
#include <gtest/gtest.h>
#include "reference/crosscheck.hpp"
#include "reference/bullet_adapter.hpp"
#include "envs/rigid/cartpole_env.hpp"
using namespace dsb;
using namespace dsb::reference;
void run(CartpoleConfig cfg, double u, double tau0, const char* what) {
  auto model = CartpoleModel::build(cfg);
  auto s = cartpole_initial_state(model, cfg);
  BulletCartpole b(cfg);
  double tau[8] = {tau0, 0, 0};
  for (int t = 0; t < 5; ++t) {
    cartpole_step(model, s, u, tau);
    b.step(u, tau);
    auto sb = b.state();
    printf("%s t%d ours x %.6f vx %.6f phi %.6f dphi %.6f | bullet x %.6f vx %.6f phi %.6f dphi %.6f  tip %.6f %.6f vs %.6f %.6f\n", what, t, s.x, s.vx, s.phi(0), s.dphi(0), sb.x, sb.vx, sb.phi(0), sb.dphi(0),
      cartpole_tip(model, s).x(), cartpole_tip(model, s).y(), b.tip().x(), b.tip().y());
  }
}
TEST(Scratch, Bullet) {
  auto cfg = CartpoleConfig::one_link();
  cfg.start_joint_angles = {0.5};
  run(cfg, 0, 0, "free");
  cfg.start_joint_angles = {};
  run(cfg, 1.0, 0, "cart");
  run(cfg, 0.0, 1.0, "torque");
}
