#include "envs/rigid/cartpole_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb {

CartpoleConfig CartpoleConfig::one_link() {
  CartpoleConfig c;
  c.links = 1;
  c.link_masses = {1.0};
  // chosen here: the design's first choice, (1.0, 2.5), is out of reach of a 1 m pole (loss floor 1.5, which
  // every optimizer hits); the 3-link target's height scaled to the chain length, 2.5/3 -> 0.8
  c.target = {1.0, 0.8};
  return c;
}

CartpoleConfig CartpoleConfig::three_links() { return CartpoleConfig{}; }

void CartpoleConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("cartpole", field, why); };
  auto positive = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be finite and > 0, got " + std::to_string(v));
  };
  if (links < 1 || links > 8) fail("links", "must be in 1..8, got " + std::to_string(links));
  if (static_cast<int>(link_masses.size()) != links)
    fail("link_masses", "must have " + std::to_string(links) + " entries, got " + std::to_string(link_masses.size()));
  for (double m : link_masses) positive("link_masses", m);
  positive("link_length", link_length);
  positive("cart_mass", cart_mass);
  if (!(std::isfinite(gravity) && gravity >= 0.0)) fail("gravity", "must be finite and >= 0");
  positive("dt", dt);
  if (steps < 1) fail("steps", "must be >= 1, got " + std::to_string(steps));
  positive("max_cart_speed", max_cart_speed);
  positive("max_torque", max_torque);
  if (!std::isfinite(target[0]) || !std::isfinite(target[1])) fail("target", "must be finite");
  if (!start_joint_angles.empty() && static_cast<int>(start_joint_angles.size()) != links)
    fail("start_joint_angles", "must be empty or have " + std::to_string(links) + " entries");
  if (!start_joint_velocities.empty() && static_cast<int>(start_joint_velocities.size()) != links)
    fail("start_joint_velocities", "must be empty or have " + std::to_string(links) + " entries");
}

nlohmann::json CartpoleConfig::to_json() const {
  return {{"links", links},
          {"link_masses", link_masses},
          {"link_length", link_length},
          {"cart_mass", cart_mass},
          {"gravity", gravity},
          {"dt", dt},
          {"steps", steps},
          {"max_cart_speed", max_cart_speed},
          {"max_torque", max_torque},
          {"target", target},
          {"start_joint_angles", start_joint_angles},
          {"start_joint_velocities", start_joint_velocities},
          {"integrator", "semi-implicit Euler"},
          {"params", "per step: cart speed, then one torque per joint (step-major)"},
          {"loss", "L2 distance of the final tip to target"}};
}

}  // namespace dsb
