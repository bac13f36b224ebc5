#include "envs/rigid/bounce_config.hpp"

#include <cmath>
#include <string>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb {

void BounceConfig::validate() const {
  const FieldCheck check("bounce");
  check.positive("radius", radius);
  check.positive("mass", mass);
  check.finite("start", start);
  check.finite("v_low", v_low);
  check.finite("v_high", v_high);
  for (int i = 0; i < 3; ++i)
    check.require(v_low[i] <= v_high[i], "v_high",
                  "must be >= v_low in every component (component " + std::to_string(i) + ")");
  check.finite("wall_x", wall_x);
  check.require(start[0] < wall_x, "wall_x", "must be > start x (the ball starts on the free side)");
  check.require(std::isfinite(gravity) && gravity >= 0.0, "gravity", "must be finite and >= 0");
  check.time_steps("duration", duration, dt);
  check.finite("target", target);
  contact.validate("bounce");
}

nlohmann::json BounceConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["steps"] = std::lround(duration / dt);
  j["surfaces"] = "ground y = 0 (normal +y), wall x = wall_x (normal -x), both infinite planes";
  j["integrator"] = "semi-implicit Euler: v += dt (g + f / m); x += dt v";
  j["params"] = "initial velocity, v = v_low + (x + 1) / 2 (v_high - v_low) per component";
  j["loss"] = "L2 distance of the final ball centre to target";
  return j;
}

}  // namespace dsb
