#pragma once
// `pinball-1x2`, `pinball-4x4`: a ball (point mass with a contact radius, no spin) dropped at rest
// on a vertical 2-D board (x right, y up) falls through a grid of paddles locked at their
// parameter angles, bouncing on them, on the walls x = 0, x = width and on the floor y = 0 under
// the penalty contact law of contact.hpp; semi-implicit Euler. Each paddle is a capsule: a segment
// of length paddle_length - paddle_thickness through its centre at its angle (0 = horizontal,
// counter-clockwise positive), inflated by paddle_thickness / 2, so it is paddle_length end to
// end and paddle_thickness thick with rounded ends (the box's corners rounded off; the MuJoCo and
// Bullet references use the same capsule). Params (rows cols, row-major): angle = max_angle x.
// Loss: L2 of the final centre to the target. The gradient comes from a reverse pass through
// every step (pinball_step_adjoint): a paddle the ball never touches gets a zero gradient.
#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"
#include "envs/rigid/ball.hpp"
#include "envs/rigid/pinball_config.hpp"

namespace dsb {

constexpr int kMaxPaddles = PinballConfig::max_paddles;  // validate() bounds rows * cols by this

using Ball2State = BallStateOf<2>;

// constants of one simulation, built from a validated config (the angles are not in it)
struct PinballModel : BallConstants {
  double width = 0.0;                    // m, walls at x = 0 and x = width, floor at y = 0
  double half_segment = 0.0;             // m, (paddle_length - paddle_thickness) / 2
  double paddle_radius = 0.0;            // m, paddle_thickness / 2
  double reach = 0.0;                    // m, half_segment + paddle_radius + radius (+ a rounding margin):
                                         // farther from a paddle centre the ball cannot touch it
  int paddles = 0;                       // rows * cols
  std::vector<Eigen::Vector2d> centres;  // paddle centres, row-major (paddles)

  static PinballModel build(const PinballConfig& cfg);
};

// unit axis (cos a, sin a) of every paddle for one parameter vector (paddles entries used)
struct PaddleAxes {
  std::array<Eigen::Vector2d, kMaxPaddles> axis;
};

// one active paddle contact of a step: d(contact force)/d(paddle angle)
struct PaddleContactGrad {
  int paddle = 0;
  Eigen::Vector2d df_dangle = Eigen::Vector2d::Zero();  // N/rad (2)
};

// what the reverse pass needs from one step: the contact Jacobians (2 x 2) and the active contacts
struct PinballStepCache : BallForceJacobians<2> {
  int walls = 0;            // active wall contacts, bit mask: 1 wall x = 0, 2 wall x = width, 4 floor
  int paddle_contacts = 0;  // entries written to the contact buffer
};

// one semi-implicit Euler step: v += dt (g + f(x, v) / m); x += dt v. With `cache` it is filled
// and the active paddle contacts go to `contacts` (capacity m.paddles, may be null without cache).
void pinball_step(const PinballModel& m, const PaddleAxes& axes, Ball2State& s, PinballStepCache* cache = nullptr,
                  PaddleContactGrad* contacts = nullptr);

// reverse of pinball_step: `adj` holds dLoss/d(state after the step) on entry and dLoss/d(state
// before it) on exit; dLoss/d(angle) of the touched paddles is added to angle_bar (m.paddles)
void pinball_step_adjoint(const PinballModel& m, const PinballStepCache& cache, const PaddleContactGrad* contacts,
                          Ball2State& adj, double* angle_bar);

// steps in which each surface touched the ball
struct PinballContactSteps {
  int left_wall = 0, right_wall = 0, floor = 0;
  std::vector<int> paddles;  // per paddle, row-major
  bool operator==(const PinballContactSteps&) const = default;
};

// buffers of one rollout: per-step caches and the active paddle contacts of all steps
struct PinballWorkspace : Workspace {
  std::vector<PinballStepCache> caches;     // steps
  std::vector<PaddleContactGrad> contacts;  // grows to the most contacts seen, then reused
};

class PinballEnv : public ConfigModelEnv<PinballConfig, PinballModel> {
 public:
  PinballEnv(std::string name, PinballConfig cfg);
  std::unique_ptr<Workspace> make_workspace() const override;
  bool renderable() const override { return true; }
  std::vector<Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_rigid.cpp

  const PinballConfig& pinball_config() const { return cfg_; }
  // physical paddle angles (rad, row-major) for the normalized parameters x
  std::vector<double> paddle_angles(std::span<const double> x) const;
  Ball2State initial_state() const;
  // the states of the rollout (steps + 1, the initial one first): used by tests and references
  std::vector<Ball2State> trajectory(std::span<const double> x) const;
  PinballContactSteps contact_steps(std::span<const double> x) const;
  // loss of a final state (NaN when it is not finite)
  double final_loss(const Ball2State& s) const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;

 private:
  PaddleAxes axes(std::span<const double> x) const;
};

// family entry for the registry: `pinball-RxC` (1x2 and 4x4 are the grid's members)
EnvFamily pinball_family(int rows, int cols);

}  // namespace dsb
