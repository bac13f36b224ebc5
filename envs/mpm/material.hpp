#pragma once
// Constitutive models of the MPM engine, each a forward update and its adjoint, per particle.
//
// Solids (PlasticineLab's p2g): F_tmp = (I + dt C) F,
// F_tmp = U diag(sigma) V^T, then
//  - `plastic`: von Mises return mapping in log (Hencky) strain: sigma clamped >= 0.05,
//    eps = log sigma, eps^ = eps - mean(eps), |eps^| = sqrt(eps^.eps^ + 1e-8),
//    dgamma = |eps^| - yield / (2 mu); if dgamma > 0: eps' = mean + k eps^ with
//    k = yield / (2 mu |eps^|) (= eps - dgamma eps^ / |eps^|), f = exp(eps'), F_new =
//    U diag(f) V^T; else (inside the yield surface) f = sigma and F_new = F_tmp, as PlasticineLab
//    keeps F_tmp there.
//  - `elastic`: no projection, f = sigma, F_new = F_tmp.
//  Fixed-corotated Kirchhoff stress with R = U V^T of F_tmp:
//    tau = 2 mu (F_new - R) F_new^T + lam J (J - 1) I = U diag(g) U^T,
//    g_i = 2 mu (f_i - 1) f_i + lam J (J - 1), J = f_0 f_1 f_2.
// Fluid (`fluid`, a viscous weakly compressible liquid for syrup; the
// "direct route" with a scalar J and no SVD): J_new = (1 + dt tr C) J,
//    tau = K J_new (J_new - 1) I + eta J_new (C + C^T - 2/3 tr C I)
// (pressure p = K (1 - J) as FluidLab's liquid with K = lambda; Newtonian deviatoric viscosity
// as Claymore's, in Kirchhoff form).
//
// Adjoints go through the SVD in its stable isotropic form (svd3.hpp: iso_uv_adjoint for F_new,
// iso_uu_adjoint for tau), with divided differences (f_i - f_j) / (sigma_i - sigma_j) computed
// without cancellation, so they stay exact when singular values are equal (at rest every
// particle has sigma = (1, 1, 1)) instead of PlasticineLab's clamped 1 / (sigma_j^2 - sigma_i^2).
#include <string>

#include <nlohmann/json.hpp>

#include "envs/mpm/mpm_types.hpp"
#include "envs/mpm/svd3.hpp"

namespace dsb::mpm {

enum class MaterialKind { elastic, plastic, fluid };

// The return mapping's constants (PlasticineLab's): the guard on sigma before the logarithm, and
// the epsilon of |eps^| = sqrt(eps^.eps^ + epsilon).
inline constexpr double kSigmaFloor = 0.05;
inline constexpr double kNormEpsilon = 1e-8;

struct Material {
  MaterialKind kind = MaterialKind::plastic;
  double youngs_modulus = 5e3;  // E (PlasticineLab default)
  double poisson_ratio = 0.2;   // nu (PlasticineLab default)
  double yield_stress = 50.0;   // plastic only (PlasticineLab default)
  double density = 1.0;         // particle mass = density x particle volume (PlasticineLab p_rho)
  double bulk_modulus = 0.0;    // fluid only: K
  double viscosity = 0.0;       // fluid only: eta (dynamic viscosity)

  double mu() const { return youngs_modulus / (2.0 * (1.0 + poisson_ratio)); }
  double lambda() const {
    return youngs_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio));
  }
  void validate(const std::string& owner, const std::string& field) const;  // ConfigError names field.x
  nlohmann::json to_json() const;
};

const char* material_kind_name(MaterialKind k);

// What the reverse pass needs from one solid particle's update.
struct SolidTape {
  Svd3 svd;           // of F_tmp
  Vec3 f;             // singular values of F_new
  Vec3 eps_hat;       // deviatoric log strain (plastic flow only)
  double k = 1.0;     // the flow's scale k (1: no flow)
  double norm = 0.0;  // |eps^| (plastic flow only)
  bool flow = false;  // the return mapping moved the state
};

// Solid update: F in = F of the particle, out = F_new; returns the Kirchhoff stress.
Mat3 solid_update(const Material& mat, const Mat3& C, double dt, Mat3& F, SolidTape& tape);

// The same in two halves, so that a caller can batch the SVDs (svd3_batch) and the return
// mapping's logarithms and exponentials (dm::log_batch, dm::exp_batch) of many particles:
// F_tmp = (I + dt C) F; then, with tapes[i].svd = svd3(F[i] = F_tmp), F[i] becomes F_new and
// tau[i] the stress, for n <= kSolidBatch particles of materials mats[i]. The same bits as
// solid_update, particle by particle.
inline Mat3 trial_deformation(const Mat3& C, double dt, const Mat3& F) { return F + dt * (C * F); }
constexpr int kSolidBatch = 64;
void solid_update_batch(const Material* const* mats, Mat3* F, SolidTape* tapes, Mat3* tau, int n);

// The Kirchhoff stress solid_update returned, from its tape (tau = U diag(g(f)) U^T).
Mat3 solid_stress(const Material& mat, const SolidTape& tape);

// Adjoint of solid_update. tau_bar = dL/dtau, F_new_bar = dL/dF_new; accumulates dL/dC into
// C_bar and writes dL/dF (of the F before the update) into F_bar.
void solid_update_adjoint(const Material& mat, const Mat3& C, const Mat3& F_before, double dt, const SolidTape& tape,
                          const Mat3& tau_bar, const Mat3& F_new_bar, Mat3& C_bar, Mat3& F_bar);

// Fluid update: J in = J of the particle, out = J_new; returns the Kirchhoff stress.
Mat3 fluid_update(const Material& mat, const Mat3& C, double dt, double& J);

// Adjoint of fluid_update: accumulates dL/dC into C_bar, returns dL/dJ (of the J before).
double fluid_update_adjoint(const Material& mat, const Mat3& C, double J_before, double dt, const Mat3& tau_bar,
                            double J_new_bar, Mat3& C_bar);

}  // namespace dsb::mpm
