#include "envs/rigid/pinball_config.hpp"

#include <cmath>
#include <string>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb {

PinballConfig PinballConfig::grid(int rows, int cols) {
  PinballConfig c;
  c.rows = rows;
  c.cols = cols;
  if (rows == 1) {
    // chosen here for a single row (measured on a 20 x 20 grid of the 1x2 params): at the
    // default row height 7.5 m with the columns at 1.4 and 6.2 m the ball reaches the second
    // paddle in 5 % of the box; one row at 6.5 m with the columns 2.8 m apart (1.4, 4.2) brings
    // that to 25 % and the 2-D landscape depends on both angles
    c.first_row_y = 6.5;
    c.last_col_x = c.first_col_x + 2.8 * (cols - 1);
  }
  return c;
}

std::array<double, 2> PinballConfig::paddle_centre(int row, int col) const {
  // rows evenly spaced from first_row_y down to last_row_y, columns from first_col_x to last_col_x
  const double y = rows == 1 ? first_row_y : first_row_y + (last_row_y - first_row_y) * row / (rows - 1);
  const double x = cols == 1 ? first_col_x : first_col_x + (last_col_x - first_col_x) * col / (cols - 1);
  return {x, y};
}

void PinballConfig::validate() const {
  const FieldCheck check("pinball");
  check.at_least("rows", rows, 1);
  check.at_least("cols", cols, 1);
  check.require(rows * cols <= max_paddles, "rows",
                "rows * cols must be <= " + std::to_string(max_paddles) + ", got " + std::to_string(rows * cols));
  check.positive("width", width);
  check.positive("height", height);
  check.positive("ball_radius", ball_radius);
  check.positive("ball_mass", ball_mass);
  check.require(2.0 * ball_radius < width, "ball_radius", "must be < width / 2");
  check.finite("start", start);
  check.require(start[0] >= ball_radius && start[0] <= width - ball_radius && start[1] >= ball_radius, "start",
                "must leave the ball inside the board, clear of the walls and the floor");
  check.positive("paddle_thickness", paddle_thickness);
  check.require(std::isfinite(paddle_length) && paddle_length > paddle_thickness, "paddle_length",
                "must be finite and > paddle_thickness");
  check.finite("first_row_y", first_row_y);
  check.finite("last_row_y", last_row_y);
  check.finite("first_col_x", first_col_x);
  check.finite("last_col_x", last_col_x);
  check.positive("max_angle", max_angle);
  check.require(std::isfinite(gravity) && gravity >= 0.0, "gravity", "must be finite and >= 0");
  check.time_steps("duration", duration, dt);
  check.finite("target", target);
  contact.validate("pinball");
}

nlohmann::json PinballConfig::to_json() const {
  nlohmann::json centres = nlohmann::json::array();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) centres.push_back(paddle_centre(r, c));
  nlohmann::json j = fields_json(*this);
  j["paddle_centres"] = centres;
  j["steps"] = std::lround(duration / dt);
  j["surfaces"] =
      "walls x = 0 (normal +x) and x = width (normal -x), floor y = 0 (normal +y), no "
      "ceiling; paddles are capsules: segment of length paddle_length - paddle_thickness "
      "through the centre at the angle (0 = horizontal, counter-clockwise positive), radius "
      "paddle_thickness / 2";
  j["integrator"] = "semi-implicit Euler: v += dt (g + f / m); x += dt v";
  j["params"] = "paddle angles row-major, angle = max_angle x";
  j["loss"] = "L2 distance of the final ball centre to target";
  return j;
}

}  // namespace dsb
