#pragma once
// What the cross-check reads from a rollout, the same way for every engine: a rollout in our
// conventions and the contact events (first impact, contact episodes, bounces) found from its
// velocities alone.
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace dsb::reference {

// one engine's rollout of one parameter vector, in our conventions
struct Rollout {
  std::string engine;                     // "ours", "mujoco" or "bullet"
  std::vector<Eigen::Vector3d> position;  // tip (cartpoles) or ball centre per state (steps + 1); z = 0 in 2-D
  std::vector<Eigen::Vector3d> velocity;  // ball velocity per state (contact setups; empty for cartpoles)
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
  std::vector<int> episode_starts;                                  // first contact step of every episode
  std::vector<int> episode_ends;                                    // the state after its last contact step
  std::vector<bool> episode_bounces;                                // whether each episode is a bounce
};
constexpr double kContactDv = 1e-6;  // m/s
constexpr int kEpisodeGap = 4;       // steps
constexpr double kBounceDv = 0.5;    // m/s
ContactEvents contact_events(const Rollout& r, const Eigen::Vector3d& gravity, double dt);

}  // namespace dsb::reference
