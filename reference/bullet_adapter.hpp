#pragma once
// Bullet 3 (double precision, `bullet-float64`) models of the rigid envs. This adapter owns every
// convention change between our envs and Bullet:
//   - frame: Bullet's usual frame is ours (y-up, gravity along -y), so points map unchanged; the
//     planar setups lie in z = 0 and our counter-clockwise angles are rotations about +z.
//   - cartpoles: a btMultiBody with a fixed base, a prismatic cart link along x and one revolute
//     link per rod. Bullet's joint coordinates are relative, like MuJoCo's: phi_i is the running
//     sum. Joint torques go in with addJointTorque (joint space, as ours). The cart is
//     velocity-controlled by a btMultiBodyJointMotor with unbounded impulse: Bullet's own
//     constraint solver finds the impulse that makes the cart's speed u at the end of the step.
//     Damping, joint friction and limits are off; one step of dt per stepSimulation.
//   - contact: ours is a penalty spring-damper; Bullet resolves contacts with impulses (sequential
//     impulses, restitution and Coulomb friction). The restitution is the one our penalty law
//     produces for a normal impact (equivalent_restitution()), friction is mu.
//   - the ball has no spin in our envs: its angular factor is 0 (and the pinball ball's linear
//     factor keeps it in the board's plane z = 0).
//
// Every function here throws std::runtime_error when the build has no Bullet
// (bullet_available() == false).
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "envs/rigid/bounce_config.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_config.hpp"
#include "envs/rigid/cartpole_dynamics.hpp"
#include "envs/rigid/cartpole_env.hpp"
#include "envs/rigid/pinball_config.hpp"
#include "envs/rigid/pinball_env.hpp"
#include "reference/engine_cartpole.hpp"

namespace dsb::reference {

// true when this build links Bullet
bool bullet_available();
// "3.24 (double)" or "none"
std::string bullet_version();

// Coefficient of restitution of our penalty law (ke, kd acting on approach only) for a ball of
// `mass`: a normal impact integrated with the env's own step (semi-implicit Euler at dt, no
// gravity), outgoing over incoming normal speed. The law is linear, so it does not depend on the
// impact speed.
double equivalent_restitution(const ContactConfig& contact, double mass, double dt);

// cartpole1 / cartpole3 as a btMultiBody
class BulletCartpole : public EngineCartpole {
 public:
  explicit BulletCartpole(const CartpoleConfig& cfg);
  ~BulletCartpole() override;
  BulletCartpole(const BulletCartpole&) = delete;
  BulletCartpole& operator=(const BulletCartpole&) = delete;
  void reset() override;
  // the cart's speed through the motor
  void step(double u, const double* tau) override;
  CartpoleState state() const override;
  // from Bullet's link transforms
  Eigen::Vector2d tip() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// bounce: a btRigidBody sphere (no rotation) against static ground and wall planes
class BulletBounce {
 public:
  explicit BulletBounce(const BounceConfig& cfg);
  ~BulletBounce();
  BulletBounce(const BulletBounce&) = delete;
  BulletBounce& operator=(const BulletBounce&) = delete;
  // rollout from the config's start with initial velocity v0 (m/s): steps + 1 states
  std::vector<BallState> trajectory(const Eigen::Vector3d& v0);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// pinball: a planar btRigidBody sphere, static capsule paddles at their angles, walls and floor
class BulletPinball {
 public:
  BulletPinball(const PinballConfig& cfg, std::span<const double> angles);
  ~BulletPinball();
  BulletPinball(const BulletPinball&) = delete;
  BulletPinball& operator=(const BulletPinball&) = delete;
  // rollout from the config's start at rest: steps + 1 states
  std::vector<Ball2State> trajectory();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dsb::reference
