#pragma once
// Constants of one MLS-MPM simulation (grid, time step, gravity, boundary): a plain struct with
// PlasticineLab's defaults (its simulator's constants), validated with messages that
// name the field, stored with every run through the task's config.
//
// The domain is the box [0, n_x dx] x [0, n_y dx] x [0, n_z dx] with grid nodes at integer
// multiples of dx. Walls: a node within `bound` cells of a face (index < bound, or > n - bound,
// PlasticineLab's asymmetric test) loses the velocity component that points out of the domain;
// on the floor (y) that component goes through Coulomb friction instead (see grid_update.hpp).
#include <array>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "envs/mpm/mpm_types.hpp"

namespace dsb::mpm {

struct MpmConfig {
  std::array<int, 3> grid = {64, 64, 64};  // nodes per axis (PlasticineLab: 64^3)
  double dx = 1.0 / 64.0;                  // grid spacing (PlasticineLab: unit cube / 64)
  double dt = 1e-4;                        // substep (PlasticineLab: 0.5e-4 / quality 0.5)
  int substeps = 19;                       // substeps per env step (PlasticineLab: floor(2e-3/dt) in
                                           // floating point = 19)
  Vec3 gravity = Vec3(0.0, -30.0, 0.0);    // PlasticineLab: (0, -1, 0) x 30
  int bound = 3;                           // wall cells (PlasticineLab: 3)
  double floor_friction = 1.5;             // PlasticineLab ground_friction: 0 = slip, >= 10 = sticky
  double grid_mass_epsilon = 1e-12;        // nodes at or below this mass are empty (PlasticineLab)
  // Extra grid nodes below index 0 on every axis (node i stores position (i - pad) dx): with
  // pad = 1 particles may sit anywhere down to 0, as PlasticineLab's, whose shapes start at y = 0,
  // and their stencils (base node floor(x / dx - 1/2) >= -1) still stay on the grid. A departure:
  // PlasticineLab has no such row; its integer cast truncates the base toward zero (0 for
  // x < dx/2) and takes the weights at fx = x / dx < 1/2 (docs/departures.md).
  int pad = 0;

  // Particles' positions are clamped to [lo, hi] per axis after advection: hi = (n - bound) dx as
  // PlasticineLab (1 - 3 dx on its unit cube); lo = 0 as PlasticineLab with pad >= 1, else dx (so
  // that a stencil never leaves the grid; the walls keep particles 3 cells away anyway).
  double clamp_low() const { return pad >= 1 ? 0.0 : dx; }
  double clamp_high(int axis) const { return (grid[axis] - bound) * dx; }

  void validate(const char* owner) const;  // throws ConfigError naming the field
  nlohmann::json to_json() const;          // fields() plus the scheme
  // the stored fields, each named once (common/config_fields.hpp); gravity as [x, y, z]
  template <class Visit>
  void fields(Visit&& visit) const {
    DSB_VISIT_FIELDS(visit, grid, dx, dt, substeps);
    visit("gravity", std::array<double, 3>{gravity.x(), gravity.y(), gravity.z()});
    DSB_VISIT_FIELDS(visit, bound, floor_friction, grid_mass_epsilon, pad);
  }
};

}  // namespace dsb::mpm
