#include "envs/mpm/mpm_config.hpp"

#include <cmath>
#include <string>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb::mpm {

void MpmConfig::validate(const char* owner) const {
  const FieldCheck check(owner);
  for (int a = 0; a < 3; ++a)
    check.require(grid[a] >= 2 * bound + 4 && grid[a] <= 1024, "grid",
                  "must have 2 bound + 4 .. 1024 nodes per axis, got " + std::to_string(grid[a]));
  check.positive("dx", dx);
  check.positive("dt", dt);
  check.at_least("substeps", substeps, 1);
  check.require(gravity.allFinite(), "gravity", "must be finite");
  check.at_least("bound", bound, 1);
  check.nonnegative("floor_friction", floor_friction);
  check.require(std::isfinite(grid_mass_epsilon) && grid_mass_epsilon >= 0.0, "grid_mass_epsilon",
                "must be finite and >= 0");
  check.require(pad >= 0 && pad <= 4, "pad", "must be 0..4, got " + std::to_string(pad));
}

nlohmann::json MpmConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["scheme"] = "MLS-MPM, quadratic B-spline, APIC affine transfer, PlasticineLab substep order";
  return j;
}

}  // namespace dsb::mpm
