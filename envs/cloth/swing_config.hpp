#pragma once
// The `swing-*` tasks (after the seed study's DiffTaichi "Swing"): a 20 x 20 cm cloth, held at the
// two corners of its front edge by anchors that follow a scripted swing (forward along +z with a
// lift), is released mid-swing and lands on the floor y = 0. Two parameterisations (swing_env.hpp):
// 16 log-stiffnesses of 4 x 4 patches (fixed motion, cloth at rest at the start), or the cloth's
// 3-D initial velocity (fixed stiffness). Every constant below is "chosen here" (the seed gives
// only the cloth size, the two held corners, the patch layout and the three losses); the env table
// in docs/envs.md, row "swing".
//
// Axes: y up, floor y = 0. The cloth starts flat and horizontal at start_height, spanning
// x in [-width/2, width/2], z in [-height, 0]; the held corners are the two vertices of the front
// edge z = 0 (grid row rows - 1), columns 0 and cols - 1.
#include <array>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"

namespace dsb::cloth {

struct SwingConfig {
  // mesh: 9 x 9 vertices, 8 x 8 cells, so each of the 4 x 4 stiffness patches is 2 x 2 cells;
  // 81 vertices x 1,600 steps cost 4.5 ms forward and 12-14 ms for a gradient episode
  // (bench_cloth, one core): 1,000 gradient episodes in 11-13 s
  int cols = 9, rows = 9;
  double width = 0.2, height = 0.2;  // m (the seed's 20 x 20 cm)
  double total_mass = 0.02;          // kg (500 g/m^2, a heavy towel), equal per vertex
  double start_height = 0.3;         // m, the flat cloth's height at t = 0

  // stiffness (N/m) of a structural spring; shear and bending springs are these fractions of the
  // structural stiffness of their patch
  double shear_ratio = 0.5, bending_ratio = 0.2;
  // patch structural stiffness range: param -1 -> k_low, +1 -> k_high, affine in log k.
  // Stability: frequency_bound (Gershgorin, cloth_model.hpp) with every patch at k_high is
  // omega_max = 1,820 rad/s, omega_max dt = 0.91 at dt 5e-4, well below symplectic Euler's 2
  // (test_swing checks it over the range). The price of that bound at 81 vertices: the cloth is
  // stretchy where it is soft. Largest structural strain while held (the flat cloth falls and
  // snaps taut under the two corners), test_swing: 0.56 with every patch at k_low, 0.27 at the
  // middle, 0.15 at k_high.
  double k_low = 10.0, k_high = 60.0;  // N/m
  // the velocity tasks hold every patch at param 0: the log-middle sqrt(k_low k_high) = 24.5 N/m
  // dashpots along the springs (N s/m), not scaled by the patch stiffness; explicit damping
  // is stable for sum(c) dt / m << 1 (here 0.28 at an interior vertex)
  double structural_damping = 0.01, shear_damping = 0.005, bending_damping = 0.002;
  // global velocity damping (1/s): v *= exp(-damping dt) per step (Taichi's cloth drag_damping 1)
  double damping = 1.0;
  double gravity = 9.81;  // m/s^2 along -y

  double dt = 5e-4;       // s, symplectic Euler
  double duration = 0.8;  // s (1,600 steps)

  // swing of the two held corners, from their start p0 with tau = min(t / swing_time, 1):
  //   p(t) = p0 + (0, lift sin(pi tau), forward (1 - cos(pi tau)) / 2)
  // released at release_time (both corners); at 0.3 s (tau 0.75) they move at 0.83 m/s forward
  // and 0.83 m/s down, 0.41 m above the floor
  double swing_time = 0.4;    // s
  double forward = 0.3;       // m along +z
  double lift = 0.15;         // m along +y
  double release_time = 0.3;  // s

  double floor_height = 0.0;  // m, floor plane y = floor_height
  // contact: the seed's velocity projection on the contact plane (1 = frictionless: only the
  // inward normal part is removed)
  double tangential_keep = 1.0;

  // velocity tasks: initial velocity of every vertex, param -1 -> v_low, +1 -> v_high per axis
  std::array<double, 3> v_low = {-1.5, -1.5, -1.5}, v_high = {1.5, 1.5, 1.5};  // m/s

  // reference params (normalized) whose final state is the target of each task: loss 0 there
  std::vector<double> stiffness_reference = {0.3,  -0.5, 0.7, -0.2, 0.0, 0.5,  -0.7, 0.2,
                                             -0.4, 0.6,  0.1, -0.6, 0.4, -0.1, 0.8,  -0.3};
  std::array<double, 3> velocity_reference = {0.2, 0.4, -0.3};

  int steps() const;         // round(duration / dt)
  int release_step() const;  // round(release_time / dt)
  // throws ConfigError("swing", field, why)
  void validate() const;
  nlohmann::json to_json() const;  // fields() plus the step counts, the swing and the integrator
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(cols, rows, width, height, total_mass, start_height, shear_ratio, bending_ratio, k_low, k_high,
                    structural_damping, shear_damping, bending_damping, damping, gravity, dt, duration, swing_time,
                    forward, lift, release_time, floor_height, tangential_keep, v_low, v_high, stiffness_reference,
                    velocity_reference)
};

}  // namespace dsb::cloth
