#include "envs/rigid/bounce_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb {

void BounceConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("bounce", field, why); };
  auto positive = [&](const std::string& field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be finite and > 0, got " + std::to_string(v));
  };
  auto finite3 = [&](const std::string& field, const std::array<double, 3>& a) {
    for (double v : a)
      if (!std::isfinite(v)) fail(field, "must be finite");
  };
  positive("radius", radius);
  positive("mass", mass);
  finite3("start", start);
  finite3("v_low", v_low);
  finite3("v_high", v_high);
  for (int i = 0; i < 3; ++i)
    if (!(v_low[i] <= v_high[i]))
      fail("v_high", "must be >= v_low in every component (component " + std::to_string(i) + ")");
  if (!std::isfinite(wall_x)) fail("wall_x", "must be finite");
  if (!(start[0] < wall_x)) fail("wall_x", "must be > start x (the ball starts on the free side)");
  if (!(std::isfinite(gravity) && gravity >= 0.0)) fail("gravity", "must be finite and >= 0");
  positive("dt", dt);
  positive("duration", duration);
  if (!(std::lround(duration / dt) >= 1)) fail("duration", "must be at least one step dt");
  finite3("target", target);
  contact.validate("bounce");
}

nlohmann::json BounceConfig::to_json() const {
  return {{"radius", radius},
          {"mass", mass},
          {"start", start},
          {"v_low", v_low},
          {"v_high", v_high},
          {"wall_x", wall_x},
          {"gravity", gravity},
          {"dt", dt},
          {"duration", duration},
          {"steps", std::lround(duration / dt)},
          {"target", target},
          {"contact", contact.to_json()},
          {"surfaces", "ground y = 0 (normal +y), wall x = wall_x (normal -x), both infinite planes"},
          {"integrator", "semi-implicit Euler: v += dt (g + f / m); x += dt v"},
          {"params", "initial velocity, v = v_low + (x + 1) / 2 (v_high - v_low) per component"},
          {"loss", "L2 distance of the final ball centre to target"}};
}

}  // namespace dsb
