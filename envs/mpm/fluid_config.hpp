#pragma once
// `fluid`: a rigid ladle with 2 DOF scoops a sugar cube out of a tank of syrup (the paper's Fluid
// task, App. B). The seed fixes the tank (0.4 x 0.4 m, 0.2 m
// high), the 2-DOF ladle (forward/back and up/down speeds), 5 segments (10 params) and the loss
//   max(0, y_w - y_cube) + 3 |xz_cube - xz_ladle| + |xz_cube - xz_axis|,  y_w = 0.2,
// heights measured from the tank floor. Everything else is chosen here, in SI units (m, s, kg,
// Pa), and stored with every run; the env table in docs/envs.md repeats it with the reasons.
//
// Geometry: the tank's inner faces are the grid's walls (PlasticineLab's 3-cell boundary): with
// dx = 0.02 m and 26 nodes per axis the walls are at 3 dx = 0.06 m and (26 - 3) dx = 0.46 m, so the
// tank is 0.40 x 0.40 m with its floor at y = 0.06 m; the domain continues above the tank's 0.2 m
// rim (to 0.46 m) so that a scooped cube can be lifted clear of it.
#include <array>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/mpm_config.hpp"

namespace dsb::mpm {

struct FluidConfig {
  MpmConfig mpm = default_mpm();
  int env_steps = 50;  // 5 segments of 10 env steps (the seed's plots: t in [0, 50))
  int segments = 5;

  // syrup: viscous, weakly compressible (material.hpp); sound speed sqrt(K / rho) = 4 m/s
  Material syrup = default_syrup();
  double syrup_depth = 0.12;         // m above the tank floor (6 cells)
  int syrup_particles_per_cell = 4;  // sampled uniformly at random (PlasticineLab's ~4 per cell)

  // sugar cube: elastic, denser than the syrup, so it rests on the floor
  Material cube = default_cube();
  double cube_size = 0.08;                       // m, edge (4 cells)
  std::array<double, 2> cube_xz = {0.30, 0.26};  // m, centre on the floor
  int cube_particles_per_axis_per_cell = 2;      // a regular lattice, 8 per cell

  // ladle: a bowl (spherical cap shell, sdf.hpp) tilted about z so that it opens forward (+x) and
  // up, plus a handle capsule; both translate together
  double bowl_radius = 0.09;         // m, mid-surface: inner diameter 0.14 m = 7 cells
  double bowl_thickness = 0.04;      // m, 2 cells (thinner walls leak: grid contact needs nodes inside)
  double bowl_rim_height = 0.0;      // hemisphere
  double bowl_tilt = -0.6;           // rad about z: the opening faces +x and up, the lip leads
  double handle_radius = 0.015;      // m
  double handle_half_length = 0.12;  // m
  std::array<double, 3> ladle_start = {0.15, 0.26, 0.26};  // m, bowl centre
  // bowl centre clamp: x keeps the bowl's mid-surface inside the walls; the lowest y lets the lip
  // scrape 4 cm into the floor's 3-cell wall layer (the bowl then reaches below the grid, where it
  // touches nothing), like a thin-edged scoop on the tank bottom
  std::array<double, 3> ladle_lower = {0.15, 0.07, 0.26};
  std::array<double, 3> ladle_upper = {0.37, 0.37, 0.26};
  double max_speed = 1.5;   // m/s: x = +-1 maps to +-1.5 m/s forward/back (x) and up/down (y)
  double friction = 0.9;    // ladle (PlasticineLab's primitive default)
  double softness = 520.0;  // 1/m: contact band ln10 / softness = 0.22 dx, as PlasticineLab's 666 at dx = 1/64

  // loss
  double rim_height = 0.2;  // y_w, m above the tank floor
  std::array<double, 2> tank_axis_xz = {0.26, 0.26};
  double ladle_weight = 3.0;  // the seed's weights
  double axis_weight = 1.0;
  std::uint64_t seed = 20221;  // particle sampling

  static MpmConfig default_mpm();
  static Material default_syrup();
  static Material default_cube();
  double floor_y() const { return mpm.bound * mpm.dx; }
  int steps_per_segment() const { return env_steps / segments; }
  void validate() const;           // throws ConfigError naming the field
  nlohmann::json to_json() const;  // fields() plus units, params and loss in words
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(mpm, env_steps, segments, syrup, syrup_depth, syrup_particles_per_cell, cube, cube_size, cube_xz,
                    cube_particles_per_axis_per_cell, bowl_radius, bowl_thickness, bowl_rim_height, bowl_tilt,
                    handle_radius, handle_half_length, ladle_start, ladle_lower, ladle_upper, max_speed, friction,
                    softness, rim_height, tank_axis_xz, ladle_weight, axis_weight, seed)
};

}  // namespace dsb::mpm
