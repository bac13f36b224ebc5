#pragma once
// The cross-check: the rigid envs (cartpole1, cartpole3, bounce, pinball-1x2, pinball-4x4) run
// for seeded parameter vectors in our simulators, MuJoCo 2.2 and Bullet 3, and every pair of
// engines is compared on what the models share (reference/README.md explains each quantity and
// tolerance):
//   - cartpoles (no contact): the tip position over the whole horizon and the final loss;
//   - contact scenes: the ball's free flight before the first impact (the same semi-implicit
//     recursion in every engine), the step of the first impact, the first impact's rebound, the
//     number of ground bounces and the final position (the contact models differ: penalty vs
//     soft constraint vs impulses, so some of these are reported without a tolerance).
// `harness crosscheck [--env NAME]` prints the table through run_crosscheck().
#include <cstdint>
#include <limits>
#include <memory>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "envs/rigid/bounce_config.hpp"

namespace dsb {

// true when this build has MuJoCo or Bullet (the rows of a missing engine are left out)
bool crosscheck_available();

// Prints the table for `envs` (empty = all five rigid envs) to `out`; returns 0 when every
// tolerance holds, 1 when one fails or no engine is built. Throws UsageError naming an env the
// cross-check does not know.
int run_crosscheck(const std::vector<std::string>& envs, std::ostream& out);

namespace reference {

// the envs the cross-check knows, in table order
const std::vector<std::string>& crosscheck_envs();

// one engine's rollout of one parameter vector, in our conventions
struct Rollout {
  std::string engine;                     // "ours", "mujoco" or "bullet"
  std::vector<Eigen::Vector3d> position;  // tip (cartpoles) or ball centre per state (steps + 1); z = 0 in 2-D
  std::vector<Eigen::Vector3d> velocity;  // ball velocity per state (contact scenes; empty for cartpoles)
  double final_loss = std::numeric_limits<double>::quiet_NaN();  // the env's loss of the final state
};

// contact events of a ball rollout, read from its velocities alone (so every engine is judged
// the same way): step t (state t -> t + 1) is a contact step when the velocity change differs
// from free flight's g dt by more than kContactDv
struct ContactEvents {
  int first_impact = -1;  // first contact step, -1 when the ball never touches anything
  int episodes = 0;       // maximal runs of contact steps (gaps of up to kEpisodeGap free steps merged)
  int bounces = 0;        // episodes whose velocity change (gravity removed) exceeds kBounceDv
                          // (a graze is an episode, not a bounce)
  double clearest_graze = std::numeric_limits<double>::infinity();  // smallest episode change (m/s)
  std::vector<int> episode_starts;  // first contact step of every episode
  std::vector<int> episode_ends;    // the state after its last contact step
  std::vector<bool> episode_bounces;  // whether each episode is a bounce
};
constexpr double kContactDv = 1e-6;  // m/s
constexpr int kEpisodeGap = 4;       // steps
constexpr double kBounceDv = 0.5;    // m/s
ContactEvents contact_events(const Rollout& r, const Eigen::Vector3d& gravity, double dt);

// What must hold between two engines on one env; a negative entry is not checked.
struct Tolerances {
  double deviation = -1.0;    // max |position difference| over the whole trajectory (m)
  double free_flight = -1.0;  // max |position difference| before the first impact (m)
  double loss = -1.0;         // |final loss difference|
  double final_position = -1.0;  // |final position difference| (m)
  int first_impact = -1;      // |first-impact step difference|
  double rebound = -1.0;      // |first rebound difference| (ratio)
  int bounces = -1;           // |difference of the number of bounces on the ground / floor|
};
// the tolerance of `engines` ("ours-mujoco", "ours-bullet", "mujoco-bullet") on `env`
Tolerances crosscheck_tolerances(const std::string& env, const std::string& engines);

// one row of the table: the worst case over the env's parameter vectors
struct CrosscheckRow {
  std::string env, engines;
  int vectors = 0;
  double deviation = 0.0, free_flight = 0.0, loss = 0.0, final_position = 0.0, rebound = 0.0;
  int first_impact = 0, bounces = 0;
  bool contact = false;  // a contact scene (free flight, impact and bounce columns apply)
  Tolerances tol;
  bool pass = true;
  std::string failure;   // which quantity failed first, with the parameter vector's index
};

// The seeded parameter vectors of an env (fixed seed, so the table is reproducible). Cartpoles:
// 8 control sequences uniform in [-0.5, 0.5]; pinballs: 12 angle vectors uniform in [-1, 1];
// bounce: 24 throws uniform in [-1, 1]^3 that are not grazing in our own simulation (see
// bounce_throw_is_clear).
std::vector<std::vector<double>> crosscheck_vectors(const std::string& env);

// Every available engine's rollout of one env for each vector; built once per env, reused for
// every vector (except the pinball's, whose paddles are placed per vector).
// A throw whose bounce count is well defined: run in our simulation for 1.25 times the horizon,
// every contact episode changes the velocity by at least 2 m/s (no grazes), none starts in the
// last 15 % of the horizon or the extra quarter (no bounce that a few steps of timing difference
// move across the end of the episode), and at each one the other surface is more than 0.3 m
// beyond the contact radius (no bounce into the corner of ground and wall).
bool bounce_throw_is_clear(const BounceConfig& cfg, std::span<const double> x);

class CrosscheckScene {
 public:
  explicit CrosscheckScene(const std::string& env);  // throws UsageError for an unknown env
  ~CrosscheckScene();
  const std::string& env() const { return env_; }
  int dim() const;
  bool contact() const;
  Eigen::Vector3d gravity() const;  // ours (m/s^2)
  double dt() const;
  Rollout ours(std::span<const double> x) const;
  Rollout mujoco(std::span<const double> x);
  Rollout bullet(std::span<const double> x);
  // the surface nearest to the ball centre p, for parameters x (the pinball's paddles depend on
  // them): "ground" and "wall" (bounce), "floor", "left wall", "right wall", "paddle R,C"
  struct Surface {
    std::string name;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // outward unit normal (ours)
    bool flat = true;  // false on a paddle's rounded end (the normal turns as the ball moves)
  };
  Surface nearest_surface(std::span<const double> x, const Eigen::Vector3d& p) const;
  // bounces (ContactEvents::bounces) that start on the ground (bounce) or the floor (pinball)
  int floor_bounces(std::span<const double> x, const Rollout& r, const ContactEvents& e) const;
  // the first impact's rebound, -(v_out . n) / (v_in . n): v_in as the first contact episode
  // starts, v_out as it ends (the ball enters and leaves at about the touching height, so this
  // is the normal restitution for every contact model), n the normal of the surface touched;
  // NaN without contact or when the first impact touches a paddle's rounded end (there the soft
  // models slide the ball around the cap during their 15-step contact while an impulse reflects
  // it at once: a different quantity, not compared)
  double rebound(std::span<const double> x, const Rollout& r, const ContactEvents& e) const;

 private:
  struct Impl;
  std::string env_;
  std::unique_ptr<Impl> impl_;
};

// the rows of the table for `envs` (empty = all), each pair of the available engines
std::vector<CrosscheckRow> crosscheck(const std::vector<std::string>& envs);
void print_crosscheck(const std::vector<CrosscheckRow>& rows, std::ostream& out);

}  // namespace reference
}  // namespace dsb
