#pragma once
// A reference setup: one rigid env as the cross-check sees it in every engine (our simulator,
// MuJoCo, Bullet), with its seeded parameter vectors and its tolerances. Each rigid env has its
// setup in its own file (cartpole_setup.cpp, bounce_setup.cpp, pinball_setup.cpp), which also
// defines the setup's registration entry; setups.cpp lists the entries, one line per env.
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "common/rng.hpp"
#include "envs/core/env.hpp"
#include "envs/rigid/bounce_config.hpp"
#include "reference/events.hpp"

namespace dsb::reference {

// What must hold between two engines on one env; a negative entry is not checked.
struct Tolerances {
  double deviation = -1.0;       // max |position difference| over the whole trajectory (m)
  double free_flight = -1.0;     // max |position difference| before the first impact (m)
  double loss = -1.0;            // |final loss difference|
  double final_position = -1.0;  // |final position difference| (m)
  int first_impact = -1;         // |first-impact step difference|
  double rebound = -1.0;         // |first rebound difference| (ratio)
  int bounces = -1;              // |difference of the number of bounces on the ground / floor|
};

class CrosscheckSetup {
 public:
  virtual ~CrosscheckSetup() = default;
  const std::string& env() const { return env_; }
  // our env, built from the config its registry family uses (a test checks they are equal)
  virtual const Env& our_env() const = 0;
  int dim() const { return our_env().dim(); }
  virtual bool contact() const = 0;             // a ball setup (events, rebound, bounces apply)
  virtual Eigen::Vector3d gravity() const = 0;  // ours (m/s^2)
  virtual double dt() const = 0;
  // the seeded parameter vectors, drawn from `rng` (crosscheck_vectors seeds it)
  virtual std::vector<std::vector<double>> vectors(Rng& rng) const = 0;
  // the tolerance of `engines` ("ours-mujoco", "ours-bullet", "mujoco-bullet")
  virtual Tolerances tolerances(const std::string& engines) const = 0;
  // one engine's rollout of the parameters x; the engine models are built once per setup
  // (the pinball's per vector: its paddles are placed by x)
  virtual Rollout ours(std::span<const double> x) const = 0;
  virtual Rollout mujoco(std::span<const double> x) = 0;
  virtual Rollout bullet(std::span<const double> x) = 0;

  // the surface nearest to the ball centre p, for parameters x (the pinball's paddles depend on
  // them): "ground" and "wall" (bounce), "floor", "left wall", "right wall", "paddle R,C"
  struct Surface {
    std::string name;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // outward unit normal (ours)
    bool flat = true;  // false on a paddle's rounded end (the normal turns as the ball moves)
  };
  // none (an empty name) in a setup without contact
  virtual Surface nearest_surface(std::span<const double> x, const Eigen::Vector3d& p) const;
  // bounces (ContactEvents::bounces) that start on the ground (bounce) or the floor (pinball)
  int floor_bounces(std::span<const double> x, const Rollout& r, const ContactEvents& e) const;
  // the first impact's rebound, -(v_out . n) / (v_in . n): v_in as the first contact episode
  // starts, v_out as it ends (the ball enters and leaves at about the touching height, so this
  // is the normal restitution for every contact model), n the normal of the surface touched;
  // NaN without contact or when the first impact touches a paddle's rounded end (there the soft
  // models slide the ball around the cap during their 15-step contact while an impulse reflects
  // it at once: a different quantity, not compared)
  double rebound(std::span<const double> x, const Rollout& r, const ContactEvents& e) const;

 protected:
  explicit CrosscheckSetup(std::string env) : env_(std::move(env)) {}

 private:
  std::string env_;
};

// What the rigid setups share: our env (EnvT, built from the setup's arguments), gravity along -y
// and the step, both read from the env's model.
template <class EnvT>
class RigidSetup : public CrosscheckSetup {
 public:
  const Env& our_env() const override { return env_; }
  Eigen::Vector3d gravity() const override { return {0.0, -env_.model().gravity, 0.0}; }
  double dt() const override { return env_.model().dt; }

 protected:
  template <class... EnvArgs>
  explicit RigidSetup(std::string name, EnvArgs&&... env_args)
      : CrosscheckSetup(std::move(name)), env_(std::forward<EnvArgs>(env_args)...) {}
  EnvT env_;
};

// n parameter vectors of dim values, uniform in [lo, hi], drawn vector by vector
std::vector<std::vector<double>> uniform_vectors(Rng& rng, int n, int dim, double lo, double hi);

// picks the nearest of candidate surfaces, considered in order (the first of equal distances)
class NearestSurface {
 public:
  void consider(const std::string& name, double distance, const Eigen::Vector3d& normal, bool flat = true);
  const CrosscheckSetup::Surface& nearest() const { return nearest_; }

 private:
  double best_ = std::numeric_limits<double>::infinity();
  CrosscheckSetup::Surface nearest_;
};

// a point of a planar setup (z = 0)
inline Eigen::Vector3d lift(const Eigen::Vector2d& p) { return {p.x(), p.y(), 0.0}; }

// the tolerances every ball setup shares (free flight, first impact, first rebound)
Tolerances ball_setup_tolerances();

// A setup's registration entry: the env's name and the setup's factory.
struct SetupEntry {
  std::string env;
  std::function<std::unique_ptr<CrosscheckSetup>()> make;
};
SetupEntry cartpole_setup(int links);          // cartpole_setup.cpp: `cartpole1`, `cartpole3`
SetupEntry bounce_setup();                     // bounce_setup.cpp: `bounce`
SetupEntry pinball_setup(int rows, int cols);  // pinball_setup.cpp: `pinball-RxC`

// the entries, in table order (setups.cpp)
const std::vector<SetupEntry>& setup_entries();
// the envs the cross-check knows, in table order
const std::vector<std::string>& crosscheck_envs();
// the setup of `env`; throws UsageError naming an env the cross-check does not know
std::unique_ptr<CrosscheckSetup> make_setup(const std::string& env);

// The seeded parameter vectors of an env (fixed seed, so the table is reproducible). Cartpoles:
// 8 control sequences uniform in [-0.5, 0.5]; pinballs: 12 angle vectors uniform in [-1, 1];
// bounce: 24 throws uniform in [-1, 1]^3 that are not grazing in our own simulation (see
// bounce_throw_is_clear).
std::vector<std::vector<double>> crosscheck_vectors(const std::string& env);
// the tolerance of `engines` ("ours-mujoco", "ours-bullet", "mujoco-bullet") on `env`
Tolerances crosscheck_tolerances(const std::string& env, const std::string& engines);

// A throw whose bounce count is well defined: run in our simulation for 1.25 times the horizon,
// every contact episode changes the velocity by at least 2 m/s (no grazes), none starts in the
// last 15 % of the horizon or the extra quarter (no bounce that a few steps of timing difference
// move across the end of the episode), and at each one the other surface is more than 0.3 m
// beyond the contact radius (no bounce into the corner of ground and wall). (bounce_setup.cpp)
bool bounce_throw_is_clear(const BounceConfig& cfg, std::span<const double> x);

}  // namespace dsb::reference
