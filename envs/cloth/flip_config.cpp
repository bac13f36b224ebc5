#include "envs/cloth/flip_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb::cloth {

int FlipConfig::segment_steps() const { return static_cast<int>(std::lround(segment_time / dt)); }
int FlipConfig::steps() const { return 5 * segment_steps() + static_cast<int>(std::lround(settle_time / dt)); }

void FlipConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("flip", field, why); };
  auto positive = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be finite and > 0, got " + std::to_string(v));
  };
  auto nonnegative = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v >= 0.0)) fail(field, "must be finite and >= 0, got " + std::to_string(v));
  };
  if (cols < 2 || rows < 2 || cols > 201 || rows > 201) fail("cols/rows", "must be in [2, 201]");
  positive("side", side);
  positive("total_mass", total_mass);
  nonnegative("start_gap", start_gap);
  nonnegative("structural_stiffness", structural_stiffness);
  nonnegative("shear_stiffness", shear_stiffness);
  nonnegative("bending_stiffness", bending_stiffness);
  nonnegative("structural_damping", structural_damping);
  nonnegative("shear_damping", shear_damping);
  nonnegative("bending_damping", bending_damping);
  nonnegative("damping", damping);
  nonnegative("gravity", gravity);
  if (!(tangential_keep >= 0.0 && tangential_keep <= 1.0)) fail("tangential_keep", "must be in [0, 1]");
  pan.validate();
  // the pancake starts on the flat bottom: its half-diagonal inside flat_radius
  if (!(0.5 * side * std::sqrt(2.0) < pan.flat_radius))
    fail("side", "the pancake's half-diagonal must be < pan.flat_radius");
  if (!(start_gap < pan.rim_height + pan.thickness)) fail("start_gap", "must be < pan.rim_height + pan.thickness");
  if (!(std::isfinite(floor_height) && floor_height < -pan.thickness))
    fail("floor_height", "must be finite and below the pan");
  positive("dt", dt);
  positive("segment_time", segment_time);
  nonnegative("settle_time", settle_time);
  if (segment_steps() < 1) fail("segment_time", "must be at least one step dt");
  for (int k = 0; k < 3; ++k)
    if (!(std::isfinite(half_range[k]) && half_range[k] >= 0.0)) fail("half_range", "must be finite and >= 0");
  if (control_steps < 1) fail("control_steps", "must be >= 1");
  if (segment_steps() % control_steps != 0) fail("control_steps", "must divide segment_time / dt");
  if (steps() % control_steps != 0) fail("control_steps", "must divide the episode's steps");
  if (flip_example.size() != 15) fail("flip_example", "must have 15 entries (5 waypoints x 3)");
  for (double x : flip_example)
    if (!(x >= -1.0 && x <= 1.0)) fail("flip_example", "must lie in [-1, 1]");
}

nlohmann::json FlipConfig::to_json() const {
  return {{"cols", cols},
          {"rows", rows},
          {"side", side},
          {"total_mass", total_mass},
          {"start_gap", start_gap},
          {"structural_stiffness", structural_stiffness},
          {"shear_stiffness", shear_stiffness},
          {"bending_stiffness", bending_stiffness},
          {"structural_damping", structural_damping},
          {"shear_damping", shear_damping},
          {"bending_damping", bending_damping},
          {"damping", damping},
          {"gravity", gravity},
          {"tangential_keep", tangential_keep},
          {"pan_radius", pan.radius},
          {"pan_flat_radius", pan.flat_radius},
          {"pan_rim_height", pan.rim_height},
          {"pan_thickness", pan.thickness},
          {"pan_profile", "h(r) = rim_height u^3, u = (r - flat_radius) / (radius - flat_radius), 0 on the disc"},
          {"floor_height", floor_height},
          {"dt", dt},
          {"segment_time", segment_time},
          {"segment_steps", segment_steps()},
          {"settle_time", settle_time},
          {"steps", steps()},
          {"half_range", half_range},
          {"control_steps", control_steps},
          {"flip_example", flip_example},
          {"integrator", "symplectic Euler mass-spring (envs/cloth/cloth_dynamics.hpp), contact velocity projection"}};
}

}  // namespace dsb::cloth
