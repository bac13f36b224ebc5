#pragma once
// `bounce` (after Warp's bounce example and the paper's App. B.1): a ball thrown from (0, 1, 0)
// must reach a target after t_max = 2 s, bouncing on the ground y = 0 and a wall at x = 2.
// Params (3): the initial velocity, x in [-1, 1]^3 mapped to vx, vz in [-10, 10] m/s and
// vy in [-10, -1] m/s (it must hit the ground first).
#include <array>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "envs/rigid/contact_config.hpp"

namespace dsb {

struct BounceConfig {
  double radius = 0.1;                                  // m, contact radius (Warp soft_contact_distance)
  double mass = 1.0;                                    // kg
  std::array<double, 3> start = {0.0, 1.0, 0.0};        // m
  std::array<double, 3> v_low = {-10.0, -10.0, -10.0};  // m/s, x = -1
  std::array<double, 3> v_high = {10.0, -1.0, 10.0};    // m/s, x = +1
  double wall_x = 2.0;                                  // m, wall plane x = wall_x facing -x
  double gravity = 9.81;                                // m/s^2 along -y
  double dt = 1.0 / 480.0;                              // s, semi-implicit Euler
  double duration = 2.0;                                // s (960 steps)
  std::array<double, 3> target = {-1.0, 0.5, 1.0};      // m (chosen here)
  ContactConfig contact;                                // ke 1e4, kd 10, mu 0.25
  void validate() const;
  nlohmann::json to_json() const;  // fields() plus steps and the model's description
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(radius, mass, start, v_low, v_high, wall_x, gravity, dt, duration, target, contact)
};

}  // namespace dsb
