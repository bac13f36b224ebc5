#pragma once
// Configuration of the cartpole tasks (cart on a rail, velocity-controlled, carrying a chain of
// uniform rods driven by joint torques). Values marked "chosen here" are ours where the paper is
// silent; all are stored with every run through to_json().
#include <array>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"

namespace dsb {

struct CartpoleConfig {
  int links = 3;
  std::vector<double> link_masses = {1.0, 0.5, 0.25};  // kg, uniform rods (chosen here)
  double link_length = 1.0;                            // m, every link (paper: 1 m)
  double cart_mass = 1.0;                              // kg; the cart is velocity-controlled, so only references use it
  double gravity = 9.81;                               // m/s^2
  double dt = 0.01;                                    // s, semi-implicit Euler step
  int steps = 100;                                     // episode length
  double max_cart_speed = 5.0;                         // m/s: x = +-1 maps to +-5 m/s (chosen here)
  double max_torque = 30.0;                            // N m: x = +-1 maps to +-30 N m (chosen here)
  std::array<double, 2> target = {1.0, 2.5};           // m, tip target relative to the rail origin (chosen here)
  std::vector<double> start_joint_angles;              // rad, relative joint angles; empty = hanging down
  std::vector<double> start_joint_velocities;          // rad/s; empty = at rest

  static CartpoleConfig one_link();     // cartpole1: 1 link of 1 kg
  static CartpoleConfig three_links();  // cartpole3: 1.0, 0.5, 0.25 kg
  void validate() const;                // throws ConfigError naming the field
  nlohmann::json to_json() const;       // fields() plus the model's description
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(links, link_masses, link_length, cart_mass, gravity, dt, steps, max_cart_speed, max_torque, target,
                    start_joint_angles, start_joint_velocities)
};

}  // namespace dsb
