#include "envs/rigid/contact_config.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb {

void ContactConfig::validate(const char* owner) const {
  auto fail = [owner](const std::string& field, const std::string& why) {
    throw ConfigError(owner, "contact." + field, why);
  };
  if (!(std::isfinite(ke) && ke > 0.0)) fail("ke", "must be finite and > 0, got " + std::to_string(ke));
  if (!(std::isfinite(kd) && kd >= 0.0)) fail("kd", "must be finite and >= 0, got " + std::to_string(kd));
  if (!(std::isfinite(mu) && mu >= 0.0)) fail("mu", "must be finite and >= 0, got " + std::to_string(mu));
  if (!(std::isfinite(friction_smoothing) && friction_smoothing > 0.0))
    fail("friction_smoothing", "must be finite and > 0, got " + std::to_string(friction_smoothing));
}

nlohmann::json ContactConfig::to_json() const {
  return {{"ke", ke},
          {"kd", kd},
          {"mu", mu},
          {"friction_smoothing", friction_smoothing},
          {"law",
           "penalty: c = max(0, r - d); f_n = max(0, ke c - kd min(v_n, 0)); "
           "f_t = -mu f_n v_t / sqrt(|v_t|^2 + friction_smoothing^2)"}};
}

}  // namespace dsb
