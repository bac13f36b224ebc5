// The MLS-MPM engine's forward pass against what must hold exactly or in closed form:
// conservation of the transfers (the APIC property), free fall as the discrete recursion, a
// resting elastic cube's compression under its weight, von Mises plasticity (permanent set past
// yield, spring-back below), and PlasticineLab's contact and floor rules.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/primitive.hpp"
#include "envs/mpm/substep.hpp"
#include "support/mpm_models.hpp"

namespace dsb {
namespace {

using mpm::Mat3;
using mpm::Vec3;
using testing::add_block;
using testing::empty_model;

double total_mass(const mpm::MpmModel& m) {
  double s = 0.0;
  for (double v : m.mass) s += v;
  return s;
}

Vec3 linear_momentum(const mpm::MpmModel& m, const std::vector<mpm::Particle>& ps) {
  Vec3 s = Vec3::Zero();
  for (int p = 0; p < m.particles(); ++p) s += m.mass[p] * ps[p].v;
  return s;
}

// APIC angular momentum: sum x_p x m_p v_p + (dx^2 / 4) m_p eps : C_p^T
Vec3 angular_momentum(const mpm::MpmModel& m, const std::vector<mpm::Particle>& ps) {
  const double D = m.config.dx * m.config.dx / 4.0;
  Vec3 s = Vec3::Zero();
  for (int p = 0; p < m.particles(); ++p) {
    const Mat3& C = ps[p].C;
    const Vec3 affine(C(2, 1) - C(1, 2), C(0, 2) - C(2, 0), C(1, 0) - C(0, 1));
    s += m.mass[p] * (ps[p].x.cross(ps[p].v) + D * affine);
  }
  return s;
}

TEST(MpmTransfers, ConserveMassAndLinearAndAngularMomentum) {
  // a spinning, stretched elastic block far from the walls, no gravity, no primitives
  auto m = empty_model(32, 1.0 / 32, 2e-4, 1, Vec3::Zero());
  // PlasticineLab's empty-node threshold (1e-12) drops the momentum of nodes the stencil barely
  // reaches (~1e-12 each); conservation is a property of the transfers, so test them without it
  m.config.grid_mass_epsilon = 0.0;
  add_block(m, "block", testing::elastic(400.0, 0.3), Vec3(0.35, 0.4, 0.38), Vec3(0.62, 0.6, 0.63), 2);
  m.finalize("test");
  Rng rng(7);
  for (auto& p : m.initial) {
    const Vec3 r = p.x - Vec3(0.5, 0.5, 0.5);
    p.v = Vec3(0.3, -0.2, 0.1) + Vec3(0.0, 0.0, 2.0).cross(r);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        p.C(i, j) = 0.5 * rng.uniform(-1.0, 1.0);
        p.F(i, j) += 0.05 * rng.uniform(-1.0, 1.0);
      }
  }
  mpm::MpmWorkspace ws(m);
  ws.reset_state(m);
  const Vec3 P0 = linear_momentum(m, ws.particles), L0 = angular_momentum(m, ws.particles);
  for (int s = 0; s < 20; ++s) mpm::substep(m, ws, serial_team(), nullptr, nullptr);
  // grid mass of the last substep = particle mass (partition of unity)
  double grid_mass = 0.0;
  {
    std::array<int, 3> lo, hi;
    for (int b : ws.bins.active) {
      m.layout.block_range(b, lo, hi);
      for (int i = lo[0]; i < hi[0]; ++i)
        for (int j = lo[1]; j < hi[1]; ++j)
          for (int k = lo[2]; k < hi[2]; ++k) grid_mass += ws.grid.mq[m.layout.node(i, j, k)].w();
    }
  }
  EXPECT_NEAR(grid_mass, total_mass(m), 1e-14 * total_mass(m));
  const Vec3 P1 = linear_momentum(m, ws.particles), L1 = angular_momentum(m, ws.particles);
  EXPECT_LE((P1 - P0).norm(), 1e-13 * P0.norm()) << "P0 " << P0.transpose() << " P1 " << P1.transpose();
  EXPECT_LE((L1 - L0).norm(), 1e-12 * L0.norm()) << "L0 " << L0.transpose() << " L1 " << L1.transpose();
  // the block did move and deform (the test is not vacuous)
  EXPECT_GT((ws.particles[0].x - m.initial[0].x).norm(), 1e-4);
}

TEST(MpmClosedForm, FreeFallFollowsTheDiscreteRecursion) {
  // an elastic cube at rest in the air: until it nears the floor every particle moves as
  // v_n = n dt g, y_n = y_0 + dt^2 g n (n + 1) / 2 (semi-implicit Euler of the grid velocity)
  const double dt = 1e-3, g = -9.81;
  auto m = empty_model(32, 1.0 / 32, dt, 10, Vec3(0.0, g, 0.0));
  m.config.grid_mass_epsilon = 0.0;  // nodes below PlasticineLab's 1e-12 would lose ~1e-8 of their speed
  // E = 10: P-wave speed 3.7 m/s, CFL 0.12 (the stress is zero in free fall; stability still matters)
  add_block(m, "cube", testing::elastic(10.0, 0.3), Vec3(0.4, 0.6, 0.4), Vec3(0.6, 0.8, 0.6), 2);
  m.finalize("test");
  mpm::MpmWorkspace ws(m);
  ws.reset_state(m);
  double y0 = 0.0;
  for (const auto& p : ws.particles) y0 += p.x.y();
  y0 /= m.particles();
  const int n = 150;  // 0.15 s: falls 0.11 m, the floor wall starts at 0.09
  for (int s = 1; s <= n; ++s) mpm::substep(m, ws, serial_team(), nullptr, nullptr);
  double y = 0.0, v = 0.0, worst_v = 0.0;
  for (const auto& p : ws.particles) {
    y += p.x.y();
    v += p.v.y();
    worst_v = std::max(worst_v, std::abs(p.v.y() - n * dt * g));
  }
  y /= m.particles();
  v /= m.particles();
  EXPECT_NEAR(v, n * dt * g, 1e-11);
  EXPECT_LT(worst_v, 1e-10);
  EXPECT_NEAR(y, y0 + dt * dt * g * n * (n + 1) / 2.0, 1e-11);
}

TEST(MpmGrid, PaddingBelowTheDomainChangesNothingButAllowsParticlesDownToZero) {
  // pad = 1 adds a layer of nodes below position 0; a model away from it runs as without (to
  // round-off: the blocks, hence the particles' memory order and the scatter's summation order,
  // shift by one node), and particles may start below dx (PlasticineLab's shapes start at y = 0)
  auto run = [](int pad, double bottom) {
    auto m = empty_model(32, 1.0 / 32, 2e-4, 10, Vec3(0.0, -9.81, 0.0));
    m.config.pad = pad;
    add_block(m, "block", testing::plastic(400.0, 0.2, 5.0), Vec3(0.4, bottom, 0.4), Vec3(0.6, bottom + 0.1, 0.6), 2);
    m.finalize("test");
    mpm::MpmWorkspace ws(m);
    ws.reset_state(m);
    for (int s = 0; s < 30; ++s) mpm::substep(m, ws, serial_team(), nullptr, nullptr);
    return ws.particles;
  };
  const auto a = run(0, 0.2), b = run(1, 0.2);
  ASSERT_EQ(a.size(), b.size());
  auto mean = [](const std::vector<mpm::Particle>& ps, bool velocity) {
    Vec3 m = Vec3::Zero();
    for (const auto& p : ps) m += velocity ? p.v : p.x;
    return Vec3(m / static_cast<double>(ps.size()));
  };
  EXPECT_LE((mean(a, false) - mean(b, false)).norm(), 1e-14);
  EXPECT_LE((mean(a, true) - mean(b, true)).norm(), 1e-13);
  EXPECT_GT(mean(a, true).norm(), 0.05) << "the block fell";
  const auto c = run(1, 0.0);  // particles from y = 1/128 up
  for (const auto& p : c) ASSERT_TRUE(p.x.allFinite());
  double lowest = 1.0;
  for (const auto& p : c) lowest = std::min(lowest, p.x.y());
  EXPECT_GE(lowest, 0.0);
  EXPECT_LT(lowest, 1.0 / 32) << "particles stay in the floor layer below dx";
}

TEST(MpmClosedForm, RestingCubeCompressesByItsWeight) {
  // An elastic cube (nu = 0: uniaxial stress) on a sticky floor under gravity. The stress at
  // height s above the floor is rho g (h - s), so the cube shortens by
  //   delta = rho g h^2 / (2 E) = h m g / (2 E A),
  // half the bottom strain m g / (E A) times h. Measured between the mean heights of the top
  // and bottom particle layers, averaged over the last half of 0.6 s (the cube oscillates about
  // its equilibrium; APIC damps little). Tolerance 15%: quadratic B-splines smear the floor
  // contact over a cell and the bottom layer sits half a cell into it.
  const double dx = 1.0 / 32, h = 8 * dx, rho = 1.0, E = 60.0, g = 10.0;
  auto m = empty_model(32, dx, 4e-4, 25, Vec3(0.0, -g, 0.0));
  m.config.floor_friction = 100.0;  // sticky
  const double floor = m.config.bound * dx;
  add_block(m, "cube", testing::elastic(E, 0.0, rho), Vec3(0.5 - h / 2, floor, 0.5 - h / 2),
            Vec3(0.5 + h / 2, floor + h, 0.5 + h / 2), 2);
  m.finalize("test");
  mpm::MpmWorkspace ws(m);
  ws.reset_state(m);
  auto layer_mean = [&](double y_ref) {
    double s = 0.0;
    int c = 0;
    for (int p = 0; p < m.particles(); ++p)
      if (std::abs(m.initial[p].x.y() - y_ref) < 1e-9) {
        s += ws.particles[p].x.y();
        ++c;
      }
    return s / c;
  };
  const double y_bottom0 = floor + dx / 4, y_top0 = floor + h - dx / 4;
  const double height0 = y_top0 - y_bottom0;
  const int env_steps = 60;  // 60 x 25 x 4e-4 = 0.6 s
  double sum = 0.0;
  int count = 0;
  for (int k = 0; k < env_steps; ++k) {
    for (int s = 0; s < m.config.substeps; ++s) mpm::substep(m, ws, serial_team(), nullptr, nullptr);
    if (k >= env_steps / 2) {
      sum += layer_mean(y_top0) - layer_mean(y_bottom0);
      ++count;
    }
  }
  const double shortening = height0 - sum / count;
  const double expected = rho * g * h * h / (2.0 * E);  // = h m g / (2 E A)
  std::printf("  resting cube: shortened %.4e, h m g / (2 E A) = %.4e (ratio %.3f)\n", shortening, expected,
              shortening / expected);
  EXPECT_NEAR(shortening, expected, 0.15 * expected) << "expected " << expected;
}

TEST(MpmPlasticity, ReturnMappingPutsTheStateOnTheYieldSurface) {
  const mpm::Material mat = testing::plastic(5e3, 0.2, 50.0);
  const double mu = mat.mu();
  Rng rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    Mat3 F = Mat3::Identity();
    const double amplitude = trial < 25 ? 0.2 : 0.002;  // past yield, then inside it
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F(i, j) += amplitude * rng.uniform(-1.0, 1.0);
    Mat3 F_new = F;
    mpm::SolidTape tape;
    mpm::solid_update(mat, Mat3::Zero(), 1e-4, F_new, tape);
    // deviatoric log strain before and after: the projection scales it by
    // k = yield / (2 mu sqrt(|dev|^2 + 1e-8)) (PlasticineLab's regularized norm)
    auto deviator = [](const Mat3& M) {
      const Vec3 eps = Eigen::JacobiSVD<Mat3>(M).singularValues().array().log();
      return Vec3(eps - Vec3::Constant(eps.mean()));
    };
    const Vec3 dev0 = deviator(F), dev1 = deviator(F_new);
    const double reg = std::sqrt(dev0.squaredNorm() + 1e-8);
    if (tape.flow) {
      EXPECT_GT(reg, mat.yield_stress / (2.0 * mu));
      EXPECT_NEAR(dev1.norm(), mat.yield_stress / (2.0 * mu) * dev0.norm() / reg, 1e-12) << "trial " << trial;
      EXPECT_NEAR(F_new.determinant(), F.determinant(), 1e-12) << "volume-preserving flow";
    } else {
      // inside the yield surface F_new is F_tmp itself, bit for bit (PlasticineLab keeps F_tmp)
      EXPECT_EQ(F_new, F) << "trial " << trial;
      EXPECT_LE(reg, mat.yield_stress / (2.0 * mu));
    }
    EXPECT_EQ(tape.flow, trial < 25) << "trial " << trial;
  }
}

TEST(MpmPlasticity, InsideTheYieldSurfaceTheStressTakesSigmaItselfEvenBelowTheLogFloor) {
  // uniform compression to 0.04 (below the 0.05 floor of the logs): no deviatoric strain, no
  // flow; F stays F_tmp and the stress is the fixed-corotated one of 0.04, not of 0.05
  const mpm::Material mat = testing::plastic(5e3, 0.2, 50.0);
  Mat3 F = 0.04 * Mat3::Identity();
  mpm::SolidTape tape;
  const Mat3 tau = mpm::solid_update(mat, Mat3::Zero(), 1e-4, F, tape);
  EXPECT_FALSE(tape.flow);
  EXPECT_EQ(F, 0.04 * Mat3::Identity());
  // tau = 2 mu (F - R) F^T + lam J (J - 1) I with R = I, J = 0.04^3
  const double J = 0.04 * 0.04 * 0.04;
  const double want = 2.0 * mat.mu() * (0.04 - 1.0) * 0.04 + mat.lambda() * J * (J - 1.0);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(tau(i, i), want, 1e-12 * std::abs(want)) << i;
  EXPECT_NEAR(tau(0, 1), 0.0, 1e-12 * std::abs(want));
}

// a block pressed by a box from above to 70% of its height, then released; returns the final
// height over the initial one
double pressed_block_height_ratio(double yield) {
  const double dx = 1.0 / 32;
  auto m = empty_model(32, dx, 2e-4, 20, Vec3::Zero());
  m.config.floor_friction = 100.0;
  const double floor = 3 * dx, h = 6 * dx;
  add_block(m, "block", testing::plastic(2e3, 0.2, yield), Vec3(0.5 - 4 * dx, floor, 0.5 - 4 * dx),
            Vec3(0.5 + 4 * dx, floor + h, 0.5 + 4 * dx), 2);
  mpm::PrimitiveSpec press;
  press.shape.kind = mpm::ShapeKind::box;
  press.shape.half_extents = Vec3(0.3, 0.05, 0.3);
  press.position = Vec3(0.5, floor + h + 0.05 + 0.25 * dx, 0.5);
  press.motion = mpm::PrimitiveMotion::translate;
  press.action_axes = {1};
  press.action_scale = {0.3 * h / 10};  // 10 env steps at action -1: down by 0.3 h
  press.friction = 0.0;
  m.primitives = {press};
  m.finalize("test");
  mpm::MpmWorkspace ws(m);
  ws.reset_state(m);
  auto top = [&] {
    double t = 0.0;
    for (const auto& p : ws.particles) t = std::max(t, p.x.y());
    return t;
  };
  const double top0 = top();
  const double down = -1.0, up = 1.0, rest = 0.0;
  for (int k = 0; k < 40; ++k) {
    const double* a = k < 10 ? &down : (k < 20 ? &up : &rest);
    for (int s = 0; s < m.config.substeps; ++s) mpm::substep(m, ws, serial_team(), a, nullptr);
  }
  return (top() - floor) / (top0 - floor);
}

TEST(MpmPlasticity, PastYieldKeepsAPermanentSetBelowYieldSpringsBack) {
  // yield / (2 mu) = 1e-3 log strain: the 30% press is far past yield
  const double plastic = pressed_block_height_ratio(4.0);
  // yield / (2 mu) = 1: the press stays elastic
  const double elastic = pressed_block_height_ratio(4e3);
  std::printf("  pressed 30%% and released: final height / initial %.3f past yield, %.3f below it\n", plastic, elastic);
  EXPECT_LT(plastic, 0.85) << "a plastic block keeps most of the 30% compression";
  EXPECT_GT(elastic, 0.95) << "an elastic block springs back";
}

TEST(MpmContact, RemovesApproachingNormalVelocityWithinTheFrictionCone) {
  mpm::PrimitiveSpec sphere;
  sphere.shape.kind = mpm::ShapeKind::sphere;
  sphere.shape.radius = 0.1;
  sphere.position = Vec3(0.5, 0.5, 0.5);
  sphere.friction = 0.4;
  const mpm::Pose pose = mpm::initial_pose(sphere);
  const mpm::ContactFrame frame = mpm::contact_frame(sphere, pose, pose, 1e-3);
  const Vec3 x(0.5, 0.59, 0.5);  // inside, normal +y
  // approaching with a large tangential part: normal part removed, tangential shortened by mu |v_n|
  Vec3 v = mpm::collide(sphere, frame, x, Vec3(2.0, -1.0, 0.0));
  EXPECT_NEAR(v.y(), 0.0, 1e-15);
  EXPECT_NEAR(v.x(), 2.0 - 0.4 * 1.0, 1e-15);
  // inside the friction cone: sticks
  v = mpm::collide(sphere, frame, x, Vec3(0.3, -1.0, 0.0));
  EXPECT_EQ(v, Vec3::Zero());
  // separating: untouched
  v = mpm::collide(sphere, frame, x, Vec3(0.3, 1.0, -0.2));
  EXPECT_EQ(v, Vec3(0.3, 1.0, -0.2));
  // outside without softness: untouched
  EXPECT_EQ(mpm::collide(sphere, frame, Vec3(0.5, 0.61, 0.5), Vec3(0.0, -1.0, 0.0)), Vec3(0.0, -1.0, 0.0));
  // with softness 666, 0.002 outside: influence exp(-1.332), blended
  sphere.softness = 666.0;
  const mpm::ContactFrame soft = mpm::contact_frame(sphere, pose, pose, 1e-3);
  v = mpm::collide(sphere, soft, Vec3(0.5, 0.602, 0.5), Vec3(0.0, -1.0, 0.0));
  EXPECT_NEAR(v.y(), -(1.0 - std::exp(-0.002 * 666.0)), 1e-12);
  // a moving primitive: the relative velocity is what is projected
  mpm::Pose moved = pose;
  moved.p += Vec3(0.0, 1e-3, 0.0);  // 1 m/s upward
  const mpm::ContactFrame moving = mpm::contact_frame(sphere, pose, moved, 1e-3);
  sphere.softness = 0.0;
  v = mpm::collide(sphere, moving, x, Vec3(0.0, 0.0, 0.0));
  EXPECT_NEAR(v.y(), 1.0, 1e-12);
}

TEST(MpmBoundary, FloorFrictionAndWallsAsPlasticineLab) {
  mpm::MpmConfig cfg;
  cfg.floor_friction = 0.5;
  const int floor_node[3] = {10, 1, 10};
  Vec3 v(1.0, -0.5, 0.0);
  mpm::apply_boundary(cfg, floor_node, v);
  const double tn = std::sqrt(1.0 + 1e-8);
  EXPECT_NEAR(v.x(), 1.0 - 0.5 * 0.5 / tn, 1e-15);
  EXPECT_EQ(v.y(), 0.0);
  const int wall_node[3] = {62, 10, 1};  // upper x wall, lower z wall
  v = Vec3(1.0, -0.5, -2.0);
  mpm::apply_boundary(cfg, wall_node, v);
  EXPECT_EQ(v, Vec3(0.0, -0.5, 0.0));
  // the adjoint against central differences at a floor node with friction
  Rng rng(5);
  for (int t = 0; t < 20; ++t) {
    const Vec3 v0(rng.uniform(-1, 1), rng.uniform(-1, -0.01), rng.uniform(-1, 1));
    const Vec3 wbar(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Vec3 g = mpm::apply_boundary_adjoint(cfg, floor_node, v0, wbar);
    for (int a = 0; a < 3; ++a) {
      Vec3 lo = v0, hi = v0;
      lo[a] -= 1e-7;
      hi[a] += 1e-7;
      mpm::apply_boundary(cfg, floor_node, lo);
      mpm::apply_boundary(cfg, floor_node, hi);
      EXPECT_NEAR(g[a], wbar.dot(hi - lo) / 2e-7, 1e-7) << "trial " << t << " axis " << a;
    }
  }
}

}  // namespace
}  // namespace dsb
