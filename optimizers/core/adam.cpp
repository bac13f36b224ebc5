#include "optimizers/core/adam.hpp"

#include <cmath>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb {

void AdamConfig::validate(const std::string& owner) const {
  const FieldCheck check(owner);
  check.require(std::isfinite(lr) && lr > 0.0, "lr", "must be > 0");
  check.require(beta1 >= 0.0 && beta1 < 1.0, "beta1", "must be in [0, 1)");
  check.require(beta2 >= 0.0 && beta2 < 1.0, "beta2", "must be in [0, 1)");
  check.require(eps > 0.0, "eps", "must be > 0");
}

nlohmann::json AdamConfig::to_json() const { return fields_json(*this); }

}  // namespace dsb
