#include "envs/rigid/contact_config.hpp"

#include "common/config_fields.hpp"
#include "common/field_check.hpp"

namespace dsb {

void ContactConfig::validate(const char* owner) const {
  const FieldCheck check(owner, "contact.");
  check.positive("ke", ke);
  check.nonnegative("kd", kd);
  check.nonnegative("mu", mu);
  check.positive("friction_smoothing", friction_smoothing);
}

nlohmann::json ContactConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["law"] =
      "penalty: c = max(0, r - d); f_n = max(0, ke c - kd min(v_n, 0)); "
      "f_t = -mu f_n v_t / sqrt(|v_t|^2 + friction_smoothing^2)";
  return j;
}

}  // namespace dsb
