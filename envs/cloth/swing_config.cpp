#include "envs/cloth/swing_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb::cloth {

int SwingConfig::steps() const { return static_cast<int>(std::lround(duration / dt)); }
int SwingConfig::release_step() const { return static_cast<int>(std::lround(release_time / dt)); }

void SwingConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("swing", field, why); };
  auto positive = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be finite and > 0, got " + std::to_string(v));
  };
  auto nonnegative = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v >= 0.0)) fail(field, "must be finite and >= 0, got " + std::to_string(v));
  };
  // patches need at least one cell each way: 4 x 4 patches over (cols - 1) x (rows - 1) cells
  if (cols < 5 || rows < 5 || cols > 201 || rows > 201) fail("cols/rows", "must be in [5, 201] (4 x 4 patches)");
  positive("width", width);
  positive("height", height);
  positive("total_mass", total_mass);
  if (!std::isfinite(start_height)) fail("start_height", "must be finite");
  nonnegative("shear_ratio", shear_ratio);
  nonnegative("bending_ratio", bending_ratio);
  positive("k_low", k_low);
  positive("k_high", k_high);
  if (!(k_low <= k_high)) fail("k_high", "must be >= k_low");
  nonnegative("structural_damping", structural_damping);
  nonnegative("shear_damping", shear_damping);
  nonnegative("bending_damping", bending_damping);
  nonnegative("damping", damping);
  nonnegative("gravity", gravity);
  positive("dt", dt);
  positive("duration", duration);
  if (steps() < 1) fail("duration", "must be at least one step dt");
  positive("swing_time", swing_time);
  if (!std::isfinite(forward)) fail("forward", "must be finite");
  if (!std::isfinite(lift)) fail("lift", "must be finite");
  nonnegative("release_time", release_time);
  if (!(release_step() <= steps())) fail("release_time", "must be <= duration");
  if (!std::isfinite(floor_height)) fail("floor_height", "must be finite");
  if (!(start_height > floor_height)) fail("start_height", "must be above floor_height");
  if (!(tangential_keep >= 0.0 && tangential_keep <= 1.0)) fail("tangential_keep", "must be in [0, 1]");
  for (int i = 0; i < 3; ++i) {
    if (!(std::isfinite(v_low[i]) && std::isfinite(v_high[i]))) fail("v_low/v_high", "must be finite");
    if (!(v_low[i] <= v_high[i])) fail("v_high", "must be >= v_low in every component");
  }
  if (stiffness_reference.size() != 16) fail("stiffness_reference", "must have 16 entries (4 x 4 patches)");
  for (double x : stiffness_reference)
    if (!(x >= -1.0 && x <= 1.0)) fail("stiffness_reference", "must lie in [-1, 1]");
  for (double x : velocity_reference)
    if (!(x >= -1.0 && x <= 1.0)) fail("velocity_reference", "must lie in [-1, 1]");
}

nlohmann::json SwingConfig::to_json() const {
  return {{"cols", cols},
          {"rows", rows},
          {"width", width},
          {"height", height},
          {"total_mass", total_mass},
          {"start_height", start_height},
          {"shear_ratio", shear_ratio},
          {"bending_ratio", bending_ratio},
          {"k_low", k_low},
          {"k_high", k_high},
          {"structural_damping", structural_damping},
          {"shear_damping", shear_damping},
          {"bending_damping", bending_damping},
          {"damping", damping},
          {"gravity", gravity},
          {"dt", dt},
          {"duration", duration},
          {"steps", steps()},
          {"swing_time", swing_time},
          {"forward", forward},
          {"lift", lift},
          {"release_time", release_time},
          {"release_step", release_step()},
          {"floor_height", floor_height},
          {"tangential_keep", tangential_keep},
          {"v_low", v_low},
          {"v_high", v_high},
          {"stiffness_reference", stiffness_reference},
          {"velocity_reference", velocity_reference},
          {"swing", "p(t) = p0 + (0, lift sin(pi tau), forward (1 - cos(pi tau)) / 2), tau = min(t / swing_time, 1)"},
          {"integrator", "symplectic Euler mass-spring (envs/cloth/cloth_dynamics.hpp), contact velocity projection"}};
}

}  // namespace dsb::cloth
