#pragma once
// `pinball-1x2`, `pinball-4x4` (after the paper's Nimble pinball): a vertical board 8 m wide and
// 10 m tall with walls at x = 0 and x = 8 and a floor at y = 0; a ball dropped at rest from
// (1.0, 9.5) falls through an n_h x n_w grid of paddles, each on a revolute joint locked at its
// parameter angle; loss = L2 of the ball's final position to the target near the bottom right.
// Params (n_h n_w): paddle angles, x in [-1, 1] mapped to [-pi/2, pi/2] (row-major; angle 0 =
// horizontal, counter-clockwise positive). Each paddle is a capsule (chosen here): a segment of
// length paddle_length - paddle_thickness through its centre, inflated by paddle_thickness / 2,
// i.e. the paddle_length x paddle_thickness box with its corners rounded off (the MuJoCo and
// Bullet references use the same capsule). No ceiling. Episode: round(duration / dt) = 1920 steps.
#include <array>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "envs/rigid/contact_config.hpp"

namespace dsb {

struct PinballConfig {
  int rows = 1, cols = 2;                               // n_h x n_w
  double width = 8.0, height = 10.0;                    // m
  double ball_radius = 0.2;                             // m (chosen here)
  double ball_mass = 1.0;                               // kg (chosen here)
  std::array<double, 2> start = {1.0, 9.5};             // m (chosen here)
  double paddle_length = 1.6, paddle_thickness = 0.15;  // m (chosen here)
  // paddle centres: rows evenly spaced from first_row_y down to last_row_y, columns from
  // first_col_x to last_col_x (a single row or column uses the first value); chosen here so that
  // the first paddle (x 0.6 .. 2.2 when flat) sits under the drop point. These defaults are the
  // 4x4's layout; grid(1, cols) moves the single row to 6.5 m and spaces the columns 2.8 m apart
  // (1x2: centres (1.4, 6.5) and (4.2, 6.5)), see grid()
  double first_row_y = 7.5, last_row_y = 2.5;
  double first_col_x = 1.4, last_col_x = 6.2;
  double max_angle = 1.5707963267948966;                        // rad, x = +-1
  double gravity = 9.81;                                        // m/s^2 along -y
  double dt = 1.0 / 480.0;                                      // s, semi-implicit Euler
  double duration = 4.0;                                        // s
  std::array<double, 2> target = {7.0, 0.5};                    // m (chosen here)
  ContactConfig contact;                                        // same law as bounce
  static constexpr int max_paddles = 64;                        // validate() bounds rows * cols by this
  static PinballConfig grid(int rows, int cols);                // `pinball-RxC`'s config
  std::array<double, 2> paddle_centre(int row, int col) const;  // m, (x, y)
  void validate() const;
  nlohmann::json to_json() const;  // fields() plus the paddle centres, steps and the model's description
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(rows, cols, width, height, ball_radius, ball_mass, start, paddle_length, paddle_thickness,
                    first_row_y, last_row_y, first_col_x, last_col_x, max_angle, gravity, dt, duration, target, contact)
};

}  // namespace dsb
