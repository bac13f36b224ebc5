#include "envs/cloth/flip_config.hpp"

#include <cmath>
#include <string>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb::cloth {

int FlipConfig::segment_steps() const { return static_cast<int>(std::lround(segment_time / dt)); }
int FlipConfig::steps() const { return 5 * segment_steps() + static_cast<int>(std::lround(settle_time / dt)); }

void FlipConfig::validate() const {
  const FieldCheck check("flip");
  check.require(cols >= 2 && rows >= 2 && cols <= 201 && rows <= 201, "cols/rows", "must be in [2, 201]");
  check.positive("side", side);
  check.positive("total_mass", total_mass);
  check.nonnegative("start_gap", start_gap);
  check.nonnegative("structural_stiffness", structural_stiffness);
  check.nonnegative("shear_stiffness", shear_stiffness);
  check.nonnegative("bending_stiffness", bending_stiffness);
  check.nonnegative("structural_damping", structural_damping);
  check.nonnegative("shear_damping", shear_damping);
  check.nonnegative("bending_damping", bending_damping);
  check.nonnegative("damping", damping);
  check.nonnegative("gravity", gravity);
  check.require(tangential_keep >= 0.0 && tangential_keep <= 1.0, "tangential_keep", "must be in [0, 1]");
  pan.validate();
  // the pancake starts on the flat bottom: its half-diagonal inside flat_radius
  check.require(0.5 * side * std::sqrt(2.0) < pan.flat_radius, "side",
                "the pancake's half-diagonal must be < pan.flat_radius");
  check.require(start_gap < pan.rim_height + pan.thickness, "start_gap", "must be < pan.rim_height + pan.thickness");
  check.require(std::isfinite(floor_height) && floor_height < -pan.thickness, "floor_height",
                "must be finite and below the pan");
  check.positive("dt", dt);
  check.positive("segment_time", segment_time);
  check.nonnegative("settle_time", settle_time);
  check.require(segment_steps() >= 1, "segment_time", "must be at least one step dt");
  for (double h : half_range) check.require(std::isfinite(h) && h >= 0.0, "half_range", "must be finite and >= 0");
  check.require(control_steps >= 1, "control_steps", "must be >= 1");
  check.require(segment_steps() % control_steps == 0, "control_steps", "must divide segment_time / dt");
  check.require(steps() % control_steps == 0, "control_steps", "must divide the episode's steps");
  check.require(flip_example.size() == 15, "flip_example", "must have 15 entries (5 waypoints x 3)");
  check.in_unit_box("flip_example", flip_example);
}

nlohmann::json FlipConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["pan_profile"] = "h(r) = rim_height u^3, u = (r - flat_radius) / (radius - flat_radius), 0 on the disc";
  j["segment_steps"] = segment_steps();
  j["steps"] = steps();
  j["integrator"] = "symplectic Euler mass-spring (envs/cloth/cloth_dynamics.hpp), contact velocity projection";
  return j;
}

}  // namespace dsb::cloth
