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
  template <class Visit>
  void fields(Visit&& visit) const {
    visit("mpm", mpm);
    visit("env_steps", env_steps);
    visit("segments", segments);
    visit("syrup", syrup);
    visit("syrup_depth", syrup_depth);
    visit("syrup_particles_per_cell", syrup_particles_per_cell);
    visit("cube", cube);
    visit("cube_size", cube_size);
    visit("cube_xz", cube_xz);
    visit("cube_particles_per_axis_per_cell", cube_particles_per_axis_per_cell);
    visit("bowl_radius", bowl_radius);
    visit("bowl_thickness", bowl_thickness);
    visit("bowl_rim_height", bowl_rim_height);
    visit("bowl_tilt", bowl_tilt);
    visit("handle_radius", handle_radius);
    visit("handle_half_length", handle_half_length);
    visit("ladle_start", ladle_start);
    visit("ladle_lower", ladle_lower);
    visit("ladle_upper", ladle_upper);
    visit("max_speed", max_speed);
    visit("friction", friction);
    visit("softness", softness);
    visit("rim_height", rim_height);
    visit("tank_axis_xz", tank_axis_xz);
    visit("ladle_weight", ladle_weight);
    visit("axis_weight", axis_weight);
    visit("seed", seed);
  }
};

}  // namespace dsb::mpm
