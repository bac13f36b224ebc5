#include "envs/cloth/swing_config.hpp"

#include <cmath>
#include <string>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb::cloth {

int SwingConfig::steps() const { return static_cast<int>(std::lround(duration / dt)); }
int SwingConfig::release_step() const { return static_cast<int>(std::lround(release_time / dt)); }

void SwingConfig::validate() const {
  const FieldCheck check("swing");
  // patches need at least one cell each way: 4 x 4 patches over (cols - 1) x (rows - 1) cells
  check.require(cols >= 5 && rows >= 5 && cols <= 201 && rows <= 201, "cols/rows",
                "must be in [5, 201] (4 x 4 patches)");
  check.positive("width", width);
  check.positive("height", height);
  check.positive("total_mass", total_mass);
  check.finite("start_height", start_height);
  check.nonnegative("shear_ratio", shear_ratio);
  check.nonnegative("bending_ratio", bending_ratio);
  check.positive("k_low", k_low);
  check.positive("k_high", k_high);
  check.require(k_low <= k_high, "k_high", "must be >= k_low");
  check.nonnegative("structural_damping", structural_damping);
  check.nonnegative("shear_damping", shear_damping);
  check.nonnegative("bending_damping", bending_damping);
  check.nonnegative("damping", damping);
  check.nonnegative("gravity", gravity);
  check.positive("dt", dt);
  check.positive("duration", duration);
  check.require(steps() >= 1, "duration", "must be at least one step dt");
  check.positive("swing_time", swing_time);
  check.finite("forward", forward);
  check.finite("lift", lift);
  check.nonnegative("release_time", release_time);
  check.require(release_step() <= steps(), "release_time", "must be <= duration");
  check.finite("floor_height", floor_height);
  check.require(start_height > floor_height, "start_height", "must be above floor_height");
  check.require(tangential_keep >= 0.0 && tangential_keep <= 1.0, "tangential_keep", "must be in [0, 1]");
  for (int i = 0; i < 3; ++i) {
    check.require(std::isfinite(v_low[i]) && std::isfinite(v_high[i]), "v_low/v_high", "must be finite");
    check.require(v_low[i] <= v_high[i], "v_high", "must be >= v_low in every component");
  }
  check.require(stiffness_reference.size() == 16, "stiffness_reference", "must have 16 entries (4 x 4 patches)");
  check.in_unit_box("stiffness_reference", stiffness_reference);
  check.in_unit_box("velocity_reference", velocity_reference);
}

nlohmann::json SwingConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["steps"] = steps();
  j["release_step"] = release_step();
  j["swing"] = "p(t) = p0 + (0, lift sin(pi tau), forward (1 - cos(pi tau)) / 2), tau = min(t / swing_time, 1)";
  j["integrator"] = "symplectic Euler mass-spring (envs/cloth/cloth_dynamics.hpp), contact velocity projection";
  return j;
}

}  // namespace dsb::cloth
