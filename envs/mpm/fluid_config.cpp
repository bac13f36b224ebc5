#include "envs/mpm/fluid_config.hpp"

#include <cmath>
#include <string>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb::mpm {

MpmConfig FluidConfig::default_mpm() {
  MpmConfig c;
  c.grid = {26, 26, 26};
  c.dx = 0.02;
  // CFL: (sound speed 4.1 m/s in the cube + ladle 1.5 m/s) dt / dx = 0.28
  c.dt = 1e-3;
  c.substeps = 8;  // env step 8 ms; episode 50 x 8 = 400 substeps = 0.4 s
  c.gravity = Vec3(0.0, -9.81, 0.0);
  c.bound = 3;
  c.floor_friction = 0.5;
  return c;
}

Material FluidConfig::default_syrup() {
  Material m;
  m.kind = MaterialKind::fluid;
  m.density = 1300.0;       // kg/m^3
  m.bulk_modulus = 2.08e4;  // Pa: sound speed 4 m/s; hydrostatic compression g h / c^2 = 7% at 0.12 m
  m.viscosity = 5.0;        // Pa s: Reynolds number rho U L / eta = 1300 x 1 x 0.1 / 5 = 26;
                            // explicit limit rho dx^2 / (6 eta) = 0.017 s >> dt
  return m;
}

Material FluidConfig::default_cube() {
  Material m;
  m.kind = MaterialKind::elastic;
  m.density = 1600.0;      // kg/m^3 (sugar 1590), above the syrup's 1300
  m.youngs_modulus = 2e4;  // Pa: P-wave speed sqrt((lam + 2 mu) / rho) = 4.1 m/s (CFL above)
  m.poisson_ratio = 0.3;
  return m;
}

void FluidConfig::validate() const {
  const FieldCheck check("fluid");
  mpm.validate("fluid");
  check.at_least("env_steps", env_steps, 1);
  check.require(segments >= 1 && env_steps % segments == 0, "segments",
                "must divide env_steps (" + std::to_string(env_steps) + "), got " + std::to_string(segments));
  syrup.validate("fluid", "syrup");
  cube.validate("fluid", "cube");
  check.require(syrup.kind == MaterialKind::fluid, "syrup.kind", "must be fluid");
  check.require(cube.kind != MaterialKind::fluid, "cube.kind", "must be elastic or plastic");
  check.positive("syrup_depth", syrup_depth);
  check.require(syrup_particles_per_cell >= 1, "syrup_particles_per_cell", "must be >= 1");
  check.positive("cube_size", cube_size);
  check.require(cube_particles_per_axis_per_cell >= 1, "cube_particles_per_axis_per_cell", "must be >= 1");
  check.positive("bowl_radius", bowl_radius);
  check.positive("bowl_thickness", bowl_thickness);
  check.positive("handle_radius", handle_radius);
  check.positive("handle_half_length", handle_half_length);
  check.positive("max_speed", max_speed);
  check.require(std::isfinite(friction) && friction >= 0.0, "friction", "must be finite and >= 0");
  check.require(std::isfinite(softness) && softness >= 0.0, "softness", "must be finite and >= 0");
  for (int a = 0; a < 3; ++a)
    check.require(ladle_lower[a] <= ladle_start[a] && ladle_start[a] <= ladle_upper[a], "ladle_start",
                  "must lie inside [ladle_lower, ladle_upper]");
  const double lo = floor_y(), hi_x = (mpm.grid[0] - mpm.bound) * mpm.dx, hi_z = (mpm.grid[2] - mpm.bound) * mpm.dx;
  check.require(cube_xz[0] - cube_size / 2 > lo && cube_xz[0] + cube_size / 2 < hi_x &&
                    cube_xz[1] - cube_size / 2 > lo && cube_xz[1] + cube_size / 2 < hi_z,
                "cube_xz", "puts the cube outside the tank");
  check.require(syrup_depth + floor_y() < (mpm.grid[1] - mpm.bound) * mpm.dx, "syrup_depth", "exceeds the domain");
}

nlohmann::json FluidConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["units"] = "m, s, kg, Pa; heights from the tank floor y = bound dx";
  j["params"] =
      "5 segments x (forward/back speed along x, up/down speed along y), x = +-1 -> +-max_speed, "
      "held for env_steps / segments env steps";
  j["loss"] =
      "max(0, rim_height - y_cube) + ladle_weight |xz_cube - xz_bowl| + axis_weight |xz_cube - "
      "tank_axis_xz|, cube = mean of its particles, at the last env step";
  return j;
}

}  // namespace dsb::mpm
