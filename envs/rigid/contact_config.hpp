#pragma once
// Penalty contact law shared by `bounce` and the pinballs (Warp's soft contact as in its 2022
// bounce example): normal force f_n = ke * penetration - kd * min(v_n, 0) (never pulling), and
// Coulomb friction against the tangential velocity with a smooth approximation where the exact
// law has no derivative: f_t = -mu f_n v_t / sqrt(|v_t|^2 + friction_smoothing^2). The exact
// Coulomb law -mu f_n v_t / |v_t| jumps at v_t = 0 (no derivative there, and an explicit step
// makes it chatter); the smooth law is viscous below about friction_smoothing and Coulomb above.
// Formulas, branches and derivatives: envs/rigid/contact.hpp.
//
// friction_smoothing (chosen here, 0.5 m/s): near v_t = 0 the smooth law is a damper of
// coefficient mu f_n / eps, and semi-implicit Euler brings v_t to rest only while
// dt mu f_n / (m eps) < 2. Above that the tangential velocity flips sign every step (chatter)
// and the derivative of the step is multiplied by about 1 - dt mu f_n / (m eps) per step
// (measured: a vertical bounce with eps = 0.01 gives dLoss/dvx ~ 1e35). Impacts reach
// f_n ~ (sqrt(ke m) + kd) |v_n| ~ 110 N per m/s (1500 N for the pinball's 13.5 m/s fall); with
// m = 1 kg, dt = 1/480 s, mu = 0.25, eps = 0.5 m/s keeps the step stable up to f_n = 1920 N.
#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"

namespace dsb {

struct ContactConfig {
  double ke = 1e4;                         // N/m, normal stiffness (Warp example)
  double kd = 10.0;                        // N s/m, normal damping on approach (Warp example)
  double mu = 0.25;                        // Coulomb friction coefficient (design)
  double friction_smoothing = 0.5;         // m/s, velocity scale of the smooth Coulomb law (chosen
                                           // here, was 1e-2: unstable stick, see above)
  void validate(const char* owner) const;  // throws ConfigError naming the field
  nlohmann::json to_json() const;          // fields() plus the law
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(ke, kd, mu, friction_smoothing)
};

}  // namespace dsb
