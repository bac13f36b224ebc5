#include "envs/rigid/pinball_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

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
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("pinball", field, why); };
  auto positive = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be finite and > 0, got " + std::to_string(v));
  };
  auto finite = [&](const std::string& field, double v) {
    if (!std::isfinite(v)) fail(field, "must be finite");
  };
  if (rows < 1) fail("rows", "must be >= 1, got " + std::to_string(rows));
  if (cols < 1) fail("cols", "must be >= 1, got " + std::to_string(cols));
  if (rows * cols > max_paddles)
    fail("rows", "rows * cols must be <= " + std::to_string(max_paddles) + ", got " + std::to_string(rows * cols));
  positive("width", width);
  positive("height", height);
  positive("ball_radius", ball_radius);
  positive("ball_mass", ball_mass);
  if (!(2.0 * ball_radius < width)) fail("ball_radius", "must be < width / 2");
  finite("start", start[0]);
  finite("start", start[1]);
  if (!(start[0] >= ball_radius && start[0] <= width - ball_radius && start[1] >= ball_radius))
    fail("start", "must leave the ball inside the board, clear of the walls and the floor");
  positive("paddle_thickness", paddle_thickness);
  if (!(std::isfinite(paddle_length) && paddle_length > paddle_thickness))
    fail("paddle_length", "must be finite and > paddle_thickness");
  finite("first_row_y", first_row_y);
  finite("last_row_y", last_row_y);
  finite("first_col_x", first_col_x);
  finite("last_col_x", last_col_x);
  positive("max_angle", max_angle);
  if (!(std::isfinite(gravity) && gravity >= 0.0)) fail("gravity", "must be finite and >= 0");
  positive("dt", dt);
  positive("duration", duration);
  if (!(std::lround(duration / dt) >= 1)) fail("duration", "must be at least one step dt");
  finite("target", target[0]);
  finite("target", target[1]);
  contact.validate("pinball");
}

nlohmann::json PinballConfig::to_json() const {
  nlohmann::json centres = nlohmann::json::array();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) centres.push_back(paddle_centre(r, c));
  return {{"rows", rows},
          {"cols", cols},
          {"width", width},
          {"height", height},
          {"ball_radius", ball_radius},
          {"ball_mass", ball_mass},
          {"start", start},
          {"paddle_length", paddle_length},
          {"paddle_thickness", paddle_thickness},
          {"first_row_y", first_row_y},
          {"last_row_y", last_row_y},
          {"first_col_x", first_col_x},
          {"last_col_x", last_col_x},
          {"paddle_centres", centres},
          {"max_angle", max_angle},
          {"gravity", gravity},
          {"dt", dt},
          {"duration", duration},
          {"steps", std::lround(duration / dt)},
          {"target", target},
          {"contact", contact.to_json()},
          {"surfaces",
           "walls x = 0 (normal +x) and x = width (normal -x), floor y = 0 (normal +y), no "
           "ceiling; paddles are capsules: segment of length paddle_length - paddle_thickness "
           "through the centre at the angle (0 = horizontal, counter-clockwise positive), radius "
           "paddle_thickness / 2"},
          {"integrator", "semi-implicit Euler: v += dt (g + f / m); x += dt v"},
          {"params", "paddle angles row-major, angle = max_angle x"},
          {"loss", "L2 distance of the final ball centre to target"}};
}

}  // namespace dsb
