#include "envs/mpm/fluid_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

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
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("fluid", field, why); };
  auto positive = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be finite and > 0, got " + std::to_string(v));
  };
  mpm.validate("fluid");
  if (env_steps < 1) fail("env_steps", "must be >= 1, got " + std::to_string(env_steps));
  if (segments < 1 || env_steps % segments != 0)
    fail("segments", "must divide env_steps (" + std::to_string(env_steps) + "), got " + std::to_string(segments));
  syrup.validate("fluid", "syrup");
  cube.validate("fluid", "cube");
  if (syrup.kind != MaterialKind::fluid) fail("syrup.kind", "must be fluid");
  if (cube.kind == MaterialKind::fluid) fail("cube.kind", "must be elastic or plastic");
  positive("syrup_depth", syrup_depth);
  if (syrup_particles_per_cell < 1) fail("syrup_particles_per_cell", "must be >= 1");
  positive("cube_size", cube_size);
  if (cube_particles_per_axis_per_cell < 1) fail("cube_particles_per_axis_per_cell", "must be >= 1");
  positive("bowl_radius", bowl_radius);
  positive("bowl_thickness", bowl_thickness);
  positive("handle_radius", handle_radius);
  positive("handle_half_length", handle_half_length);
  positive("max_speed", max_speed);
  if (!(std::isfinite(friction) && friction >= 0.0)) fail("friction", "must be finite and >= 0");
  if (!(std::isfinite(softness) && softness >= 0.0)) fail("softness", "must be finite and >= 0");
  for (int a = 0; a < 3; ++a)
    if (!(ladle_lower[a] <= ladle_start[a] && ladle_start[a] <= ladle_upper[a]))
      fail("ladle_start", "must lie inside [ladle_lower, ladle_upper]");
  const double lo = floor_y(), hi_x = (mpm.grid[0] - mpm.bound) * mpm.dx, hi_z = (mpm.grid[2] - mpm.bound) * mpm.dx;
  if (!(cube_xz[0] - cube_size / 2 > lo && cube_xz[0] + cube_size / 2 < hi_x && cube_xz[1] - cube_size / 2 > lo &&
        cube_xz[1] + cube_size / 2 < hi_z))
    fail("cube_xz", "puts the cube outside the tank");
  if (!(syrup_depth + floor_y() < (mpm.grid[1] - mpm.bound) * mpm.dx)) fail("syrup_depth", "exceeds the domain");
}

nlohmann::json FluidConfig::to_json() const {
  return {{"mpm", mpm.to_json()},
          {"env_steps", env_steps},
          {"segments", segments},
          {"syrup", syrup.to_json()},
          {"syrup_depth", syrup_depth},
          {"syrup_particles_per_cell", syrup_particles_per_cell},
          {"cube", cube.to_json()},
          {"cube_size", cube_size},
          {"cube_xz", cube_xz},
          {"cube_particles_per_axis_per_cell", cube_particles_per_axis_per_cell},
          {"bowl_radius", bowl_radius},
          {"bowl_thickness", bowl_thickness},
          {"bowl_rim_height", bowl_rim_height},
          {"bowl_tilt", bowl_tilt},
          {"handle_radius", handle_radius},
          {"handle_half_length", handle_half_length},
          {"ladle_start", ladle_start},
          {"ladle_lower", ladle_lower},
          {"ladle_upper", ladle_upper},
          {"max_speed", max_speed},
          {"friction", friction},
          {"softness", softness},
          {"rim_height", rim_height},
          {"tank_axis_xz", tank_axis_xz},
          {"ladle_weight", ladle_weight},
          {"axis_weight", axis_weight},
          {"seed", seed},
          {"units", "m, s, kg, Pa; heights from the tank floor y = bound dx"},
          {"params",
           "5 segments x (forward/back speed along x, up/down speed along y), x = +-1 -> +-max_speed, "
           "held for env_steps / segments env steps"},
          {"loss",
           "max(0, rim_height - y_cube) + ladle_weight |xz_cube - xz_bowl| + axis_weight |xz_cube - "
           "tank_axis_xz|, cube = mean of its particles, at the last env step"}};
}

}  // namespace dsb::mpm
