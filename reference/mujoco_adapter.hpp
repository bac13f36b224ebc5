#pragma once
// MuJoCo 2.2 models of the rigid envs. This adapter owns every convention change between our
// envs and MuJoCo, and nothing outside it needs to know them:
//   - frame: ours is y-up (gravity along -y); MuJoCo's is z-up. A point (x, y, z) of ours is
//     (x, -z, y) in MuJoCo (a rotation by +90 degrees about x, so handedness is kept); the planar
//     setups (cartpoles, pinball) live in MuJoCo's x-z plane, and our counter-clockwise angle
//     (about +z of ours) is a rotation about MuJoCo's -y axis.
//   - cartpole angles: ours are absolute link angles from hanging down; MuJoCo's hinges are
//     relative (joint) angles, so phi_i = theta_1 + ... + theta_i. Our joint torque tau_j acts on
//     joint j, which is exactly MuJoCo's joint-space force on hinge j.
//   - cart: ours is velocity-controlled (the cart reaches the commanded speed u within the step).
//     MuJoCo gets the generalized force on the slide joint that produces a_cart = (u - v)/dt
//     exactly, computed each step from its own mass matrix and bias forces (see MujocoCartpole).
//   - contact: ours is a penalty spring-damper; MuJoCo's is a soft constraint. The mapping of
//     ke, kd, mu to solref / solimp / friction is mujoco_contact_params() (reference/README.md explains it).
//   - the ball has no spin in our envs: MuJoCo's ball is a body with slide joints only (3 in
//     bounce, 2 in the pinball plane), so it cannot rotate at all.
// The MJCF is generated from the env configs, never kept by hand, and compiled from memory
// through MuJoCo's virtual file system.
//
// Every function here throws std::runtime_error when the build has no MuJoCo
// (mujoco_available() == false).
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

// MuJoCo's own types, declared here so that this header does not need mujoco.h
struct mjModel_;
struct mjData_;

namespace dsb::reference {

// true when this build links MuJoCo
bool mujoco_available();
// "2.2.2" (the library actually loaded), or "none"
std::string mujoco_version();

// frame change for points and vectors: ours (y-up) <-> MuJoCo (z-up)
Eigen::Vector3d to_mujoco(const Eigen::Vector3d& ours);
Eigen::Vector3d from_mujoco(const Eigen::Vector3d& mj);

// soft-contact parameters standing in for our penalty law (ContactConfig) on a ball of `mass`
struct MujocoContactParams {
  double stiffness = 0.0;  // solref[0] = -stiffness (direct format), 1/s^2 (= ke / m)
  double damping = 0.0;    // solref[1] = -damping, 1/s (= kd / (2 m): see reference/README.md)
  double impedance = 0.0;  // solimp d0 = dwidth (constant impedance)
  double friction = 0.0;   // sliding friction coefficient (= mu)
};
MujocoContactParams mujoco_contact_params(const ContactConfig& contact, double mass);

// MJCF text generated from the configs
std::string cartpole_mjcf(const CartpoleConfig& cfg);
std::string bounce_mjcf(const BounceConfig& cfg);
// the paddles are placed at `angles` (rad, row-major, rows x cols entries)
std::string pinball_mjcf(const PinballConfig& cfg, std::span<const double> angles);

// an mjModel compiled from MJCF text and one mjData for it
class MujocoSim {
 public:
  // compiles the text through a virtual file system; throws std::runtime_error with MuJoCo's
  // message when it does not compile
  explicit MujocoSim(const std::string& mjcf);
  ~MujocoSim();
  MujocoSim(MujocoSim&&) noexcept;
  MujocoSim& operator=(MujocoSim&&) noexcept;
  MujocoSim(const MujocoSim&) = delete;
  MujocoSim& operator=(const MujocoSim&) = delete;

  const mjModel_* model() const;
  mjData_* data() const;
  // mj_resetData: qpos0, zero velocities, time 0
  void reset();
  // true when MuJoCo raised no warning (bad qpos/qvel/qacc, which also reset the data)
  bool healthy() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// cartpole1 / cartpole3 in MuJoCo: a slide joint for the cart along x and a hinge per link
class MujocoCartpole : public EngineCartpole {
 public:
  explicit MujocoCartpole(const CartpoleConfig& cfg);
  // relative joint angles and velocities as the config gives them, cart at the origin
  void reset() override;
  void step(double u, const double* tau) override;
  CartpoleState state() const override;
  // from MuJoCo's kinematics (a site at the last link's end)
  Eigen::Vector2d tip() const override;
  const MujocoSim& sim() const { return sim_; }

 private:
  MujocoSim sim_;
  std::vector<double> mass_matrix_;  // dense M (nv x nv), scratch
  int tip_site_ = -1;                // id of the site at the chain's end
};

// bounce in MuJoCo: a slide-only ball, ground and wall planes, explicit contact pairs
class MujocoBounce {
 public:
  explicit MujocoBounce(const BounceConfig& cfg);
  // rollout from the config's start with initial velocity v0 (ours, m/s): steps + 1 states
  std::vector<BallState> trajectory(const Eigen::Vector3d& v0);
  // the final state only (no allocation per step): used by the finite-difference benchmark
  BallState final_state(const Eigen::Vector3d& v0);
  const MujocoSim& sim() const { return sim_; }

 private:
  void start(const Eigen::Vector3d& v0);
  BallState read() const;
  BounceConfig cfg_;
  MujocoSim sim_;
  int steps_ = 0;
};

// pinball in MuJoCo: a ball on two slide joints in the board's plane, capsule paddles at their
// locked angles (static geoms), wall and floor planes
class MujocoPinball {
 public:
  MujocoPinball(const PinballConfig& cfg, std::span<const double> angles);
  // rollout from the config's start at rest: steps + 1 states
  std::vector<Ball2State> trajectory();
  const MujocoSim& sim() const { return sim_; }

 private:
  PinballConfig cfg_;
  MujocoSim sim_;
  int steps_ = 0;
};

}  // namespace dsb::reference
