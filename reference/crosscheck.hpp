#pragma once
// The cross-check: the rigid envs (cartpole1, cartpole3, bounce, pinball-1x2, pinball-4x4) run
// for seeded parameter vectors in our simulators, MuJoCo 2.2 and Bullet 3, and every pair of
// engines is compared on what the models share (reference/README.md explains each quantity and
// tolerance):
//   - cartpoles (no contact): the tip position over the whole horizon and the final loss;
//   - contact scenes: the ball's free flight before the first impact (the same semi-implicit
//     recursion in every engine), the step of the first impact, the number of bounces and the
//     final position (the contact models differ: penalty vs soft constraint vs impulses).
// `harness crosscheck [--env NAME]` prints the table through run_crosscheck().
#include <cstdint>
#include <limits>
#include <memory>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

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
  int bounces = 0;        // episodes that reverse the ball's approach: the velocity change over the
                          // episode exceeds kBounceDv (grazes and resting contact excluded)
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
  int bounces = -1;           // |bounce-count difference|
};
// the tolerance of `engines` ("ours-mujoco", "ours-bullet", "mujoco-bullet") on `env`
Tolerances crosscheck_tolerances(const std::string& env, const std::string& engines);

// one row of the table: the worst case over the env's parameter vectors
struct CrosscheckRow {
  std::string env, engines;
  int vectors = 0;
  double deviation = 0.0, free_flight = 0.0, loss = 0.0, final_position = 0.0;
  int first_impact = 0, bounces = 0;
  bool contact = false;  // a contact scene (free flight, impact and bounce columns apply)
  Tolerances tol;
  bool pass = true;
  std::string failure;   // which quantity failed first, with the parameter vector's index
};

// the seeded parameter vectors of an env (fixed seed, so the table is reproducible)
std::vector<std::vector<double>> crosscheck_vectors(const std::string& env);

// Every available engine's rollout of one env for each vector; built once per env, reused for
// every vector (except the pinball's, whose paddles are placed per vector).
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
