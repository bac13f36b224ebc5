// reference/: MuJoCo 2.2 and Bullet 3 models of the rigid envs against our simulators, with the
// real libraries. The cross-check's tolerances as tests: contact-free cartpoles to 1e-6 (MuJoCo,
// the requirement) and 1e-9 (Bullet, from its measured 1e-13); contact setups on what the models
// share (free flight, first impact, first rebound, ground bounces, Bullet's final position); the
// MJCF follows the config; the event detector on hand-made rollouts. A build without an engine
// skips that engine's tests.
#include <cmath>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_env.hpp"
#include "envs/rigid/pinball_env.hpp"
#include "reference/bullet_adapter.hpp"
#include "reference/crosscheck.hpp"
#include "reference/mujoco_adapter.hpp"

#if DSB_HAVE_MUJOCO
#include <mujoco/mujoco.h>
#endif

namespace dsb::reference {
namespace {

#define REQUIRE_MUJOCO() \
  if (!mujoco_available()) GTEST_SKIP() << "built without MuJoCo (DSB_WITH_MUJOCO)"
#define REQUIRE_BULLET() \
  if (!bullet_available()) GTEST_SKIP() << "built without Bullet (DSB_WITH_BULLET)"

const std::vector<std::string> kContactEnvs = {"bounce", "pinball-1x2", "pinball-4x4"};

// one engine's rollout of every seeded vector of an env
std::vector<Rollout> rollouts(CrosscheckSetup& setup, const std::string& engine) {
  std::vector<Rollout> out;
  for (const auto& x : crosscheck_vectors(setup.env())) {
    if (engine == "ours") out.push_back(setup.ours(x));
    if (engine == "mujoco") out.push_back(setup.mujoco(x));
    if (engine == "bullet") out.push_back(setup.bullet(x));
  }
  return out;
}

// max |position difference| over all states of all vectors
double worst_deviation(const std::vector<Rollout>& a, const std::vector<Rollout>& b) {
  double worst = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].position.size(), b[k].position.size());
    for (std::size_t t = 0; t < a[k].position.size(); ++t)
      worst = std::max(worst, (a[k].position[t] - b[k].position[t]).norm());
  }
  return worst;
}

// a planar rollout of `steps` states: free flight from v0, with an extra velocity change dv[t]
// applied in the steps listed (the event detector sees only velocities)
Rollout hand_made(const Eigen::Vector3d& v0, double dt, const Eigen::Vector3d& g,
                  const std::vector<std::pair<int, Eigen::Vector3d>>& kicks, int steps) {
  Rollout r;
  Eigen::Vector3d p(0.0, 1.0, 0.0), v = v0;
  r.position.push_back(p);
  r.velocity.push_back(v);
  for (int t = 0; t < steps; ++t) {
    v += dt * g;
    for (const auto& [step, dv] : kicks)
      if (step == t) v += dv;
    p += dt * v;
    r.position.push_back(p);
    r.velocity.push_back(v);
  }
  return r;
}

// ---------------------------------- conventions ---------------------------------------------

TEST(ReferenceFrames, MujocoFrameIsARotationWithOurUpAsItsZ) {
  const Eigen::Vector3d ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  EXPECT_EQ(to_mujoco(ey), ez);  // our up is MuJoCo's up
  EXPECT_EQ(to_mujoco(ex), ex);
  Eigen::Matrix3d R;
  R << to_mujoco(ex), to_mujoco(ey), to_mujoco(ez);
  EXPECT_DOUBLE_EQ(R.determinant(), 1.0);  // a rotation: handedness and angles kept
  const Eigen::Vector3d p(0.3, -1.2, 2.5);
  EXPECT_EQ(from_mujoco(to_mujoco(p)), p);
}

// ---------------------------------- cartpoles: MuJoCo ---------------------------------------

TEST(ReferenceMujoco, CartpoleMjcfComesFromTheConfig) {
  REQUIRE_MUJOCO();
#if DSB_HAVE_MUJOCO
  CartpoleConfig cfg = CartpoleConfig::three_links();
  const MujocoSim sim(cartpole_mjcf(cfg));
  const mjModel* m = sim.model();
  ASSERT_EQ(m->nq, 4);  // cart slide + 3 hinges
  ASSERT_EQ(m->nv, 4);
  for (int i = 0; i < 3; ++i) {
    const int body = mj_name2id(m, mjOBJ_BODY, ("link" + std::to_string(i + 1)).c_str());
    ASSERT_GE(body, 0);
    EXPECT_DOUBLE_EQ(m->body_mass[body], cfg.link_masses[i]);
    // uniform rod: m L^2 / 12 about its centre in the swing plane (MuJoCo's y axis)
    EXPECT_NEAR(m->body_inertia[3 * body + 1], cfg.link_masses[i] * cfg.link_length * cfg.link_length / 12.0, 1e-12);
    EXPECT_NEAR(m->body_ipos[3 * body + 2], -0.5 * cfg.link_length, 1e-12);  // centre of the rod
  }
  EXPECT_EQ(m->opt.timestep, cfg.dt);
  EXPECT_EQ(m->opt.gravity[2], -cfg.gravity);
  EXPECT_EQ(m->opt.integrator, mjINT_EULER);
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_CONTACT);
  for (int j = 0; j < m->njnt; ++j) EXPECT_EQ(m->jnt_limited[j], 0);
  for (int d = 0; d < m->nv; ++d) {
    EXPECT_EQ(m->dof_damping[d], 0.0);
    EXPECT_EQ(m->dof_armature[d], 0.0);
    EXPECT_EQ(m->dof_frictionloss[d], 0.0);
  }

  // the config drives the model: a different link mass and length give a different mjModel
  cfg.link_masses[1] = 0.7;
  cfg.link_length = 1.5;
  const MujocoSim changed(cartpole_mjcf(cfg));
  const int link2 = mj_name2id(changed.model(), mjOBJ_BODY, "link2");
  EXPECT_DOUBLE_EQ(changed.model()->body_mass[link2], 0.7);
  EXPECT_NE(changed.model()->body_mass[link2], m->body_mass[link2]);
  MujocoCartpole hanging(cfg);
  EXPECT_NEAR(hanging.tip().x(), 0.0, 1e-12);
  EXPECT_NEAR(hanging.tip().y(), -4.5, 1e-12);  // three links of 1.5 m hanging down
#endif
}

TEST(ReferenceMujoco, CartpoleTipMatchesOursToOneMicrometre) {
  REQUIRE_MUJOCO();
  for (const std::string env : {"cartpole1", "cartpole3"}) {
    const auto owned = make_setup(env);
    CrosscheckSetup& setup = *owned;
    const double worst = worst_deviation(rollouts(setup, "ours"), rollouts(setup, "mujoco"));
    EXPECT_LE(worst, 1e-6) << env;  // the requirement, over the whole 100-step horizon
    EXPECT_EQ(crosscheck_tolerances(env, "ours-mujoco").deviation, 1e-6);
    RecordProperty(env + "_mujoco_tip_deviation", std::to_string(worst));
  }
}

// the three-link cartpole from a start away from hanging down, with joint velocities
CartpoleConfig cartpole3_started_aside() {
  CartpoleConfig cfg = CartpoleConfig::three_links();
  cfg.start_joint_angles = {0.4, -0.3, 0.2};
  cfg.start_joint_velocities = {0.5, 1.0, -2.0};
  return cfg;
}

// the state an engine (MujocoCartpole, BulletCartpole) built from cfg reads back (cart, absolute
// angles and rates) and its tip are ours after every one of 60 steps of varying commands
template <class Engine>
void expect_engine_reads_back_our_states(Engine& engine, const CartpoleConfig& cfg) {
  const CartpoleModel model = CartpoleModel::build(cfg);
  CartpoleState ours = cartpole_initial_state(model, cfg);
  for (int t = 0; t < 60; ++t) {
    const double u = 2.0 * std::sin(0.1 * t), tau[3] = {5.0 * std::cos(0.2 * t), -3.0, 1.0};
    cartpole_step(model, ours, u, tau);
    engine.step(u, tau);
    const CartpoleState s = engine.state();
    ASSERT_NEAR(s.x, ours.x, 1e-12) << t;
    ASSERT_NEAR(s.vx, u, 1e-12) << t;  // velocity control: the cart's speed is the command, exactly
    for (int i = 0; i < 3; ++i) {
      ASSERT_NEAR(s.phi(i), ours.phi(i), 1e-10) << t;
      ASSERT_NEAR(s.dphi(i), ours.dphi(i), 1e-10) << t;
    }
    ASSERT_NEAR((engine.tip() - cartpole_tip(model, ours)).norm(), 0.0, 1e-10) << t;
  }
}

TEST(ReferenceMujoco, CartpoleStateReadsBackInOurConventions) {
  REQUIRE_MUJOCO();
  const CartpoleConfig cfg = cartpole3_started_aside();
  MujocoCartpole mj(cfg);
  EXPECT_NEAR(mj.state().phi(2), 0.3, 1e-15);  // absolute = running sum of the joint angles
  EXPECT_NEAR(mj.state().dphi(2), -0.5, 1e-15);
  expect_engine_reads_back_our_states(mj, cfg);
}

// ---------------------------------- cartpoles: Bullet ---------------------------------------

TEST(ReferenceBullet, CartpoleTipMatchesOurs) {
  REQUIRE_BULLET();
  for (const std::string env : {"cartpole1", "cartpole3"}) {
    const auto owned = make_setup(env);
    CrosscheckSetup& setup = *owned;
    const double worst = worst_deviation(rollouts(setup, "ours"), rollouts(setup, "bullet"));
    // measured 1.1e-13 (btMultiBody steps semi-implicit Euler like ours, in double precision)
    EXPECT_LE(worst, crosscheck_tolerances(env, "ours-bullet").deviation) << env;
    EXPECT_EQ(crosscheck_tolerances(env, "ours-bullet").deviation, 1e-9);
  }
}

TEST(ReferenceBullet, CartpoleStateReadsBackInOurConventions) {
  REQUIRE_BULLET();
  const CartpoleConfig cfg = cartpole3_started_aside();
  const CartpoleModel model = CartpoleModel::build(cfg);
  BulletCartpole bt(cfg);
  EXPECT_NEAR((bt.tip() - cartpole_tip(model, cartpole_initial_state(model, cfg))).norm(), 0.0, 1e-12);
  expect_engine_reads_back_our_states(bt, cfg);  // Bullet's motor row reaches the commanded speed
}

// ---------------------------------- cartpoles: the parameter map ---------------------------

// the engines take each step's controls from the env's own map (CartpoleEnv::controls), here a
// map other than the default one, and refuse an env whose config their model was not built from
TEST(ReferenceCartpole, EnginesFollowTheEnvsParameterMap) {
  if (!mujoco_available() && !bullet_available()) GTEST_SKIP() << "built without MuJoCo and Bullet";
  CartpoleConfig cfg = CartpoleConfig::one_link();
  cfg.max_cart_speed = 2.0;
  cfg.max_torque = 7.0;
  const CartpoleEnv env("cartpole1", cfg);
  const CartpoleEnv other("cartpole1", CartpoleConfig::one_link());
  Rng rng(11);
  std::vector<double> x(env.dim());
  for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
  std::vector<Eigen::Vector2d> ours;
  for (const auto& s : env.trajectory(x)) ours.push_back(cartpole_tip(env.model(), s));
  auto worst = [&](const std::vector<Eigen::Vector2d>& tips) {
    EXPECT_EQ(tips.size(), ours.size());
    double w = 0.0;
    for (std::size_t t = 0; t < tips.size() && t < ours.size(); ++t) w = std::max(w, (tips[t] - ours[t]).norm());
    return w;
  };
  if (mujoco_available()) {
    MujocoCartpole mj(cfg);
    EXPECT_LE(worst(mj.tip_trajectory(env, x)), 1e-6);
    EXPECT_THROW(mj.tip_trajectory(other, x), std::invalid_argument);
  }
  if (bullet_available()) {
    BulletCartpole bt(cfg);
    EXPECT_LE(worst(bt.tip_trajectory(env, x)), 1e-9);
    EXPECT_THROW(bt.tip_trajectory(other, x), std::invalid_argument);
  }
}

// ---------------------------------- contact setups ------------------------------------------

TEST(ReferenceContact, EventDetectorOnHandMadeRollouts) {
  const double dt = 1.0 / 480.0;
  const Eigen::Vector3d g(0.0, -9.81, 0.0);
  // free flight only: no contact at all
  const ContactEvents none = contact_events(hand_made({1, -2, 0}, dt, g, {}, 200), g, dt);
  EXPECT_EQ(none.first_impact, -1);
  EXPECT_EQ(none.episodes, 0);
  // an impulse at step 40, a soft 10-step impact from step 100, a graze (0.1 m/s) at step 150
  std::vector<std::pair<int, Eigen::Vector3d>> kicks = {{40, {0, 8, 0}}, {150, {0, 0.1, 0}}};
  for (int t = 100; t < 110; ++t) kicks.push_back({t, {0.1, 0.9, 0}});
  const ContactEvents e = contact_events(hand_made({1, -2, 0}, dt, g, kicks, 200), g, dt);
  EXPECT_EQ(e.first_impact, 40);
  EXPECT_EQ(e.episodes, 3);
  EXPECT_EQ(e.bounces, 2);  // the graze is below kBounceDv
  EXPECT_EQ(e.episode_starts, (std::vector<int>{40, 100, 150}));
  EXPECT_EQ(e.episode_ends, (std::vector<int>{41, 110, 151}));
  EXPECT_NEAR(e.clearest_graze, 0.1, 1e-9);
}

TEST(ReferenceContact, EquivalentRestitutionOfOurPenaltyLaw) {
  ContactConfig c;  // ke 1e4, kd 10: damping ratio 0.05, acting on approach only
  const double e = equivalent_restitution(c, 1.0, 1.0 / 480.0);
  EXPECT_GT(e, 0.90);
  EXPECT_LT(e, 0.96);
  c.kd = 0.0;  // an undamped spring gives the speed back (semi-implicit Euler: to within 2 %)
  EXPECT_NEAR(equivalent_restitution(c, 1.0, 1.0 / 480.0), 1.0, 0.02);
  c.kd = 40.0;
  EXPECT_LT(equivalent_restitution(c, 1.0, 1.0 / 480.0), e);
}

TEST(ReferenceContact, MujocoContactPairsComeFromTheConfig) {
  REQUIRE_MUJOCO();
#if DSB_HAVE_MUJOCO
  BounceConfig cfg;
  cfg.contact.ke = 2e4;
  cfg.contact.mu = 0.4;
  const MujocoSim sim(bounce_mjcf(cfg));
  const mjModel* m = sim.model();
  ASSERT_EQ(m->npair, 2);  // ground and wall
  for (int p = 0; p < m->npair; ++p) {
    EXPECT_DOUBLE_EQ(m->pair_solref[2 * p], -2e4 / cfg.mass);  // direct format: -stiffness
    EXPECT_DOUBLE_EQ(m->pair_solref[2 * p + 1], -0.5 * cfg.contact.kd / cfg.mass);
    EXPECT_DOUBLE_EQ(m->pair_friction[5 * p], 0.4);
    EXPECT_EQ(m->pair_dim[p], 3);
  }
  const int ball = mj_name2id(m, mjOBJ_GEOM, "ball");
  EXPECT_DOUBLE_EQ(m->geom_size[3 * ball], cfg.radius);
  EXPECT_EQ(m->nv, 3);  // slide joints only: the ball cannot spin
  EXPECT_EQ(m->opt.timestep, cfg.dt);
#endif
}

TEST(ReferenceContact, MujocoPinballPaddlesAreTheConfigsCapsules) {
  REQUIRE_MUJOCO();
#if DSB_HAVE_MUJOCO
  const PinballConfig cfg = PinballConfig::grid(4, 4);
  std::vector<double> angles(16);
  for (int k = 0; k < 16; ++k) angles[k] = -1.5 + 0.2 * k;
  const MujocoSim sim(pinball_mjcf(cfg, angles));
  const mjModel* m = sim.model();
  EXPECT_EQ(m->nv, 2);  // the ball moves in the board's plane only
  EXPECT_EQ(m->npair, 16 + 3);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      const std::string name = "paddle_" + std::to_string(r) + "_" + std::to_string(c);
      const int g = mj_name2id(m, mjOBJ_GEOM, name.c_str());
      ASSERT_GE(g, 0) << name;
      EXPECT_EQ(m->geom_type[g], mjGEOM_CAPSULE);
      EXPECT_NEAR(m->geom_size[3 * g], 0.5 * cfg.paddle_thickness, 1e-12);
      EXPECT_NEAR(m->geom_size[3 * g + 1], 0.5 * (cfg.paddle_length - cfg.paddle_thickness), 1e-12);
      const auto centre = cfg.paddle_centre(r, c);
      const Eigen::Vector3d pos(m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]);
      EXPECT_NEAR((from_mujoco(pos) - Eigen::Vector3d(centre[0], centre[1], 0.0)).norm(), 0.0, 1e-12);
      // the capsule's axis (MuJoCo: its local z) is the paddle's direction at its angle
      mjtNum axis[3];
      const mjtNum z[3] = {0, 0, 1};
      mju_rotVecQuat(axis, z, m->geom_quat + 4 * g);
      const Eigen::Vector3d ours = from_mujoco(Eigen::Vector3d(axis[0], axis[1], axis[2]));
      const double a = angles[r * 4 + c];
      EXPECT_NEAR(std::abs(ours.dot(Eigen::Vector3d(std::cos(a), std::sin(a), 0.0))), 1.0, 1e-9);
    }
#endif
}

// before the first impact every engine runs the same semi-implicit Euler recursion
TEST(ReferenceContact, FreeFlightIsExactAndImpactsStartTogether) {
  for (const auto& env : kContactEnvs) {
    const auto owned = make_setup(env);
    CrosscheckSetup& setup = *owned;
    const auto ours = rollouts(setup, "ours");
    for (const std::string engine : {"mujoco", "bullet"}) {
      if ((engine == "mujoco" && !mujoco_available()) || (engine == "bullet" && !bullet_available())) continue;
      const auto theirs = rollouts(setup, engine);
      for (std::size_t k = 0; k < ours.size(); ++k) {
        const ContactEvents eo = contact_events(ours[k], setup.gravity(), setup.dt());
        const ContactEvents et = contact_events(theirs[k], setup.gravity(), setup.dt());
        ASSERT_GE(eo.first_impact, 0) << env << " vector " << k << " never touches anything";
        EXPECT_LE(std::abs(eo.first_impact - et.first_impact), 1) << env << " " << engine << " " << k;
        const int last = std::min(eo.first_impact, et.first_impact);
        for (int t = 0; t <= last; ++t)
          ASSERT_LE((ours[k].position[t] - theirs[k].position[t]).norm(), 1e-9)
              << env << " " << engine << " vector " << k << " state " << t;
      }
    }
  }
}

// the first impact's normal restitution: our penalty law, MuJoCo's soft constraint (damping
// halved) and Bullet's restitution impulse (equivalent_restitution) agree on flat faces
TEST(ReferenceContact, FirstReboundAgreesOnFlatFaces) {
  for (const auto& env : kContactEnvs) {
    const auto owned = make_setup(env);
    CrosscheckSetup& setup = *owned;
    const auto xs = crosscheck_vectors(env);
    int compared = 0;
    for (const auto& x : xs) {
      const Rollout ours = setup.ours(x);
      const double e_ours = setup.rebound(x, ours, contact_events(ours, setup.gravity(), setup.dt()));
      if (std::isnan(e_ours)) continue;  // a paddle's rounded end
      ++compared;
      EXPECT_GT(e_ours, 0.85) << env;
      if (mujoco_available()) {
        const Rollout mj = setup.mujoco(x);
        EXPECT_NEAR(setup.rebound(x, mj, contact_events(mj, setup.gravity(), setup.dt())), e_ours, 0.03) << env;
      }
      if (bullet_available()) {
        const Rollout bt = setup.bullet(x);
        EXPECT_NEAR(setup.rebound(x, bt, contact_events(bt, setup.gravity(), setup.dt())), e_ours, 0.03) << env;
      }
    }
    EXPECT_GE(compared, static_cast<int>(xs.size()) / 2) << env;
  }
}

// clear throws (not grazing, no bounce at the horizon, no corner): the same number of ground
// bounces in every engine; Bullet's final position within 0.75 m of ours
TEST(ReferenceContact, BounceCountsAndFinalPositions) {
  const auto owned = make_setup("bounce");
  CrosscheckSetup& setup = *owned;
  const auto xs = crosscheck_vectors("bounce");
  ASSERT_EQ(xs.size(), 24u);
  int several = 0, walls = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const auto& x = xs[k];
    EXPECT_TRUE(bounce_throw_is_clear(BounceConfig{}, x));
    const Rollout ours = setup.ours(x);
    const ContactEvents eo = contact_events(ours, setup.gravity(), setup.dt());
    const int n = setup.floor_bounces(x, ours, eo);
    EXPECT_GE(n, 1);
    several += n >= 2;
    walls += eo.bounces > n;
    if (mujoco_available()) {
      const Rollout mj = setup.mujoco(x);
      EXPECT_EQ(setup.floor_bounces(x, mj, contact_events(mj, setup.gravity(), setup.dt())), n) << k;
    }
    if (bullet_available()) {
      const Rollout bt = setup.bullet(x);
      const ContactEvents eb = contact_events(bt, setup.gravity(), setup.dt());
      EXPECT_EQ(setup.floor_bounces(x, bt, eb), n) << k;
      EXPECT_EQ(eb.bounces, eo.bounces) << k;  // wall bounces too: both have Coulomb friction
      EXPECT_LE((bt.position.back() - ours.position.back()).norm(), 0.75) << k;
    }
  }
  // not a vacuous test: throws that bounce more than once, and throws that reach the wall
  EXPECT_GE(several, 5);
  EXPECT_GE(walls, 2);
}

// ---------------------------------- the table -----------------------------------------------

TEST(Crosscheck, EveryToleranceHoldsAndEveryEngineIsNamed) {
  if (!crosscheck_available()) {
    std::ostringstream out;
    EXPECT_EQ(run_crosscheck({}, out), 1);
    GTEST_SKIP() << "built without MuJoCo and Bullet";
  }
  std::ostringstream out;
  const int rc = run_crosscheck({}, out);
  const std::string table = out.str();
  std::cout << table;
  EXPECT_EQ(rc, 0) << table;
  EXPECT_EQ(table.find("FAIL ("), std::string::npos);
  for (const auto& env : crosscheck_envs()) EXPECT_NE(table.find(env + " "), std::string::npos) << env;
  EXPECT_EQ(table.find("ours-mujoco") != std::string::npos, mujoco_available());
  EXPECT_EQ(table.find("ours-bullet") != std::string::npos, bullet_available());
  EXPECT_EQ(table.find("mujoco-bullet") != std::string::npos, mujoco_available() && bullet_available());
}

TEST(Crosscheck, OneEnvIsDeterministicAndUnknownNamesAreUsageErrors) {
  if (!crosscheck_available()) GTEST_SKIP() << "built without MuJoCo and Bullet";
  std::ostringstream a, b;
  EXPECT_EQ(run_crosscheck({"cartpole1"}, a), 0);
  EXPECT_EQ(run_crosscheck({"cartpole1"}, b), 0);
  EXPECT_EQ(a.str(), b.str());  // fixed seed: the same table every time
  EXPECT_EQ(a.str().find("cartpole3"), std::string::npos);
  std::ostringstream c;
  EXPECT_THROW(run_crosscheck({"cartpole2"}, c), UsageError);
  EXPECT_THROW(run_crosscheck({"sphere-10"}, c), UsageError);
}

// each setup's env is the one the harness runs: the registry's env of that name, same config
TEST(Crosscheck, EverySetupsEnvIsTheRegistrysEnv) {
  ASSERT_EQ(crosscheck_envs(),
            (std::vector<std::string>{"cartpole1", "cartpole3", "bounce", "pinball-1x2", "pinball-4x4"}));
  for (const auto& name : crosscheck_envs()) {
    const auto setup = make_setup(name);
    const auto env = make_env(name);
    EXPECT_EQ(setup->env(), name);
    EXPECT_EQ(setup->our_env().name(), name);
    EXPECT_EQ(setup->our_env().config(), env->config()) << name;
    EXPECT_EQ(setup->dim(), env->dim()) << name;
  }
  EXPECT_THROW(make_setup("sphere-10"), UsageError);
}

TEST(Crosscheck, TolerancesAreTheDocumentedOnes) {
  const Tolerances t = crosscheck_tolerances("bounce", "ours-bullet");
  EXPECT_EQ(t.free_flight, 1e-9);
  EXPECT_EQ(t.first_impact, 1);
  EXPECT_EQ(t.bounces, 0);
  EXPECT_EQ(t.final_position, 0.75);
  EXPECT_LT(crosscheck_tolerances("bounce", "ours-mujoco").final_position, 0.0);  // reported only
  EXPECT_LT(crosscheck_tolerances("pinball-4x4", "ours-bullet").final_position, 0.0);
}

}  // namespace
}  // namespace dsb::reference
