#include "optimizers/core/adam.hpp"

#include <cmath>

#include "common/error.hpp"

namespace dsb {

void AdamConfig::validate(const std::string& owner) const {
  if (!(std::isfinite(lr) && lr > 0.0)) throw ConfigError(owner, "lr", "must be > 0");
  if (!(beta1 >= 0.0 && beta1 < 1.0)) throw ConfigError(owner, "beta1", "must be in [0, 1)");
  if (!(beta2 >= 0.0 && beta2 < 1.0)) throw ConfigError(owner, "beta2", "must be in [0, 1)");
  if (!(eps > 0.0)) throw ConfigError(owner, "eps", "must be > 0");
}

nlohmann::json AdamConfig::to_json() const { return {{"lr", lr}, {"beta1", beta1}, {"beta2", beta2}, {"eps", eps}}; }

}  // namespace dsb
