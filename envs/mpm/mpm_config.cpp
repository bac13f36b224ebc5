#include "envs/mpm/mpm_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb::mpm {

void MpmConfig::validate(const char* owner) const {
  auto fail = [&](const std::string& field, const std::string& why) { throw ConfigError(owner, field, why); };
  for (int a = 0; a < 3; ++a)
    if (grid[a] < 2 * bound + 4 || grid[a] > 1024)
      fail("grid", "must have 2 bound + 4 .. 1024 nodes per axis, got " + std::to_string(grid[a]));
  if (!(std::isfinite(dx) && dx > 0.0)) fail("dx", "must be finite and > 0, got " + std::to_string(dx));
  if (!(std::isfinite(dt) && dt > 0.0)) fail("dt", "must be finite and > 0, got " + std::to_string(dt));
  if (substeps < 1) fail("substeps", "must be >= 1, got " + std::to_string(substeps));
  if (!gravity.allFinite()) fail("gravity", "must be finite");
  if (bound < 1) fail("bound", "must be >= 1, got " + std::to_string(bound));
  if (!(std::isfinite(floor_friction) && floor_friction >= 0.0))
    fail("floor_friction", "must be finite and >= 0, got " + std::to_string(floor_friction));
  if (!(std::isfinite(grid_mass_epsilon) && grid_mass_epsilon >= 0.0))
    fail("grid_mass_epsilon", "must be finite and >= 0");
  if (pad < 0 || pad > 4) fail("pad", "must be 0..4, got " + std::to_string(pad));
}

nlohmann::json MpmConfig::to_json() const {
  return {{"grid", grid},
          {"dx", dx},
          {"dt", dt},
          {"substeps", substeps},
          {"gravity", {gravity.x(), gravity.y(), gravity.z()}},
          {"bound", bound},
          {"floor_friction", floor_friction},
          {"grid_mass_epsilon", grid_mass_epsilon},
          {"pad", pad},
          {"scheme", "MLS-MPM, quadratic B-spline, APIC affine transfer, PlasticineLab substep order"}};
}

}  // namespace dsb::mpm
