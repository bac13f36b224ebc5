#include "envs/mpm/material.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <cmath>

#include "common/det_math.hpp"
#include "common/error.hpp"

namespace dsb::mpm {

namespace {

constexpr double kSeriesRadius = 1e-3;  // below this relative gap, divided differences by series

// ((1 + r)^k - 1) / r for |r| <= kSeriesRadius: the binomial series to r^5 (truncation < 1e-18)
double power_quotient_series(double k, double r) {
  double term = k, sum = k;
  for (int n = 1; n <= 5; ++n) {
    term *= (k - n) / (n + 1) * r;
    sum += term;
  }
  return sum;
}

// Singular values of F_new after the return mapping, and what its derivatives need.
struct PlasticMap {
  Vec3 f, eps_hat;
  double k = 1.0, norm = 0.0;
  bool flow = false;
};

// Derivatives of a flowing particle's singular-value map sigma -> f = exp(mean + k eps^):
// dfds(i, j) = d f_i / d sigma_j and the divided differences dd(i, j) = (f_i - f_j) /
// (sigma_i - sigma_j) (their limit when equal). Without flow f = sigma: the identity and ones.
void plastic_derivatives(const Vec3& sigma, const SolidTape& t, Mat3& dfds, Mat3& dd) {
  const Vec3& f = t.f;
  Vec3 inv;  // d log(sigma_c) / d sigma: 0 where the floor holds
  for (int i = 0; i < 3; ++i) inv[i] = sigma[i] > kSigmaFloor ? 1.0 / sigma[i] : 0.0;
  // d eps'_i / d eps_j = 1/3 + k (delta_ij - 1/3) - k eps^_i eps^_j / |eps^|^2
  const double n2 = t.norm * t.norm;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double de = 1.0 / 3.0 + t.k * ((i == j ? 1.0 : 0.0) - 1.0 / 3.0) - t.k * t.eps_hat[i] * t.eps_hat[j] / n2;
      dfds(i, j) = f[i] * de * inv[j];
    }
  dd = Mat3::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      const bool ci = sigma[i] > kSigmaFloor, cj = sigma[j] > kSigmaFloor;
      if (!ci && !cj) {
        dd(i, j) = 0.0;  // both at the floor: f_i = f_j in a neighbourhood
      } else if (ci && cj) {
        // f_i / f_j = (sigma_i / sigma_j)^k (k = 1 without flow): with r = sigma_i / sigma_j - 1,
        // (f_i - f_j) / (sigma_i - sigma_j) = f_j / sigma_j ((1 + r)^k - 1) / r
        const double r = (sigma[i] - sigma[j]) / sigma[j];
        dd(i, j) = std::abs(r) <= kSeriesRadius ? f[j] / sigma[j] * power_quotient_series(t.k, r)
                                                : (f[i] - f[j]) / (sigma[i] - sigma[j]);
      } else {
        dd(i, j) = (f[i] - f[j]) / (sigma[i] - sigma[j]);  // one at the floor: the gap is real
      }
    }
}

// Fixed-corotated g_i = 2 mu (f_i - 1) f_i + lam J (J - 1) and dg/df.
void corotated_diagonal(double mu, double lam, const Vec3& f, Vec3& g, Mat3* dgdf) {
  const double J = f[0] * f[1] * f[2];
  const double vol = lam * J * (J - 1.0);
  for (int i = 0; i < 3; ++i) g[i] = 2.0 * mu * (f[i] - 1.0) * f[i] + vol;
  if (dgdf) {
    const Vec3 J_over(f[1] * f[2], f[0] * f[2], f[0] * f[1]);  // J / f_j without division
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        (*dgdf)(i, j) = (i == j ? 2.0 * mu * (2.0 * f[i] - 1.0) : 0.0) + lam * (2.0 * J - 1.0) * J_over[j];
  }
}

}  // namespace

const char* material_kind_name(MaterialKind k) {
  switch (k) {
    case MaterialKind::elastic: return "elastic";
    case MaterialKind::plastic: return "plastic";
    case MaterialKind::fluid: return "fluid";
  }
  return "?";
}

void Material::validate(const std::string& owner, const std::string& field) const {
  auto fail = [&](const std::string& f, const std::string& why) { throw ConfigError(owner, field + "." + f, why); };
  auto positive = [&](const std::string& f, double v) {
    if (!(std::isfinite(v) && v > 0.0)) fail(f, "must be finite and > 0, got " + std::to_string(v));
  };
  positive("density", density);
  if (kind == MaterialKind::fluid) {
    positive("bulk_modulus", bulk_modulus);
    if (!(std::isfinite(viscosity) && viscosity >= 0.0)) fail("viscosity", "must be finite and >= 0");
  } else {
    positive("youngs_modulus", youngs_modulus);
    if (!(std::isfinite(poisson_ratio) && poisson_ratio > -1.0 && poisson_ratio < 0.5))
      fail("poisson_ratio", "must be in (-1, 0.5), got " + std::to_string(poisson_ratio));
    if (kind == MaterialKind::plastic) positive("yield_stress", yield_stress);
  }
}

nlohmann::json Material::to_json() const {
  nlohmann::json j = {{"kind", material_kind_name(kind)}, {"density", density}};
  if (kind == MaterialKind::fluid) {
    j["bulk_modulus"] = bulk_modulus;
    j["viscosity"] = viscosity;
  } else {
    j["youngs_modulus"] = youngs_modulus;
    j["poisson_ratio"] = poisson_ratio;
    if (kind == MaterialKind::plastic) j["yield_stress"] = yield_stress;
  }
  return j;
}

Mat3 solid_update(const Material& mat, const Mat3& C, double dt, Mat3& F, SolidTape& tape) {
  // F_tmp = (I + dt C) F
  F = trial_deformation(C, dt, F);
  tape.svd = svd3(F);
  const Material* m = &mat;
  Mat3 tau;
  solid_update_batch(&m, &F, &tape, &tau, 1);
  return tau;
}

void solid_update_batch(const Material* const* mats, Mat3* F, SolidTape* tapes, Mat3* tau, int n) {
  if (n > kSolidBatch) throw std::invalid_argument("solid_update_batch: at most kSolidBatch particles");
  // von Mises return mapping in log strain: the logarithms of every plastic particle at once
  std::array<double, 3 * kSolidBatch> args{}, logs{};
  int m = 0;
  for (int i = 0; i < n; ++i)
    if (mats[i]->kind == MaterialKind::plastic)
      for (int a = 0; a < 3; ++a) args[m++] = std::max(tapes[i].svd.sigma[a], kSigmaFloor);
  dm::log_batch(args.data(), logs.data(), m);
  // the flow's targets mean + k eps^, then their exponentials at once
  int used = 0, e = 0;
  for (int i = 0; i < n; ++i) {
    SolidTape& t = tapes[i];
    t.flow = false;
    t.k = 1.0;
    if (mats[i]->kind != MaterialKind::plastic) continue;
    const Vec3 eps(logs[used], logs[used + 1], logs[used + 2]);
    used += 3;
    const double mu = mats[i]->mu();
    const double mean = (eps[0] + eps[1] + eps[2]) / 3.0;
    t.eps_hat = eps - Vec3::Constant(mean);
    t.norm = std::sqrt(t.eps_hat.squaredNorm() + kNormEpsilon);
    const double dgamma = t.norm - mats[i]->yield_stress / (2.0 * mu);
    if (dgamma > 0.0) {
      t.flow = true;
      t.k = mats[i]->yield_stress / (2.0 * mu * t.norm);
      for (int a = 0; a < 3; ++a) args[e++] = mean + t.k * t.eps_hat[a];
    }
  }
  dm::exp_batch(args.data(), logs.data(), e);
  e = 0;
  for (int i = 0; i < n; ++i) {
    SolidTape& t = tapes[i];
    const Vec3& sigma = t.svd.sigma;
    if (t.flow) {
      // F_new = U diag(exp(mean + k eps^)) V^T: projected onto the yield surface
      t.f = Vec3(logs[e], logs[e + 1], logs[e + 2]);
      e += 3;
      F[i] = t.svd.U * t.f.asDiagonal() * t.svd.V.transpose();
    } else {
      // F_new = F_tmp, already in F: elastic, or plastic inside the yield surface (as PlasticineLab,
      // which keeps F_tmp as it is there; the stress takes sigma itself, not max(sigma, 0.05))
      t.f = sigma;
    }
    // tau = U diag(g) U^T
    tau[i] = solid_stress(*mats[i], t);
  }
}

Mat3 solid_stress(const Material& mat, const SolidTape& tape) {
  Vec3 g;
  corotated_diagonal(mat.mu(), mat.lambda(), tape.f, g, nullptr);
  return tape.svd.U * g.asDiagonal() * tape.svd.U.transpose();
}

void solid_update_adjoint(const Material& mat, const Mat3& C, const Mat3& F_before, double dt, const SolidTape& tape,
                          const Mat3& tau_bar, const Mat3& F_new_bar, Mat3& C_bar, Mat3& F_bar) {
  const double mu = mat.mu(), lam = mat.lambda();
  const Vec3& sigma = tape.svd.sigma;
  Mat3 dfds, dd;
  if (tape.flow) {
    plastic_derivatives(sigma, tape, dfds, dd);
  } else {  // f = sigma
    dfds.setIdentity();
    dd.setOnes();
    dd.diagonal().setZero();
  }
  // tau = U diag(g(f(sigma))) U^T: dg/dsigma = dg/df df/dsigma, and the divided differences
  // (g_i - g_j) / (sigma_i - sigma_j) = 2 mu (f_i + f_j - 1) dd_ij (the volume term cancels)
  Vec3 g;
  Mat3 dgdf;
  corotated_diagonal(mu, lam, tape.f, g, &dgdf);
  const Mat3 dgds = dgdf * dfds;
  Mat3 ddg = Mat3::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j) ddg(i, j) = 2.0 * mu * (tape.f[i] + tape.f[j] - 1.0) * dd(i, j);
  Mat3 F_tmp_bar = iso_uu_adjoint(tape.svd, dgds, ddg, tau_bar);
  // F_new = U diag(f) V^T (flow) or F_tmp (no flow, or elastic)
  if (tape.flow)
    F_tmp_bar += iso_uv_adjoint(tape.svd, tape.f, dfds, dd, F_new_bar);
  else
    F_tmp_bar += F_new_bar;
  // F_tmp = (I + dt C) F
  C_bar += dt * (F_tmp_bar * F_before.transpose());
  F_bar = F_tmp_bar + dt * (C.transpose() * F_tmp_bar);
}

Mat3 fluid_update(const Material& mat, const Mat3& C, double dt, double& J) {
  const double trace = C.trace();
  // J_new = (1 + dt tr C) J
  J = (1.0 + dt * trace) * J;
  // tau = K J (J - 1) I + eta J (C + C^T - 2/3 tr C I)
  Mat3 tau = mat.viscosity * J * (C + C.transpose());
  const double diag = mat.bulk_modulus * J * (J - 1.0) - mat.viscosity * J * (2.0 / 3.0) * trace;
  tau.diagonal().array() += diag;
  return tau;
}

double fluid_update_adjoint(const Material& mat, const Mat3& C, double J_before, double dt, const Mat3& tau_bar,
                            double J_new_bar, Mat3& C_bar) {
  const double trace = C.trace();
  const double J = (1.0 + dt * trace) * J_before;
  const double K = mat.bulk_modulus, eta = mat.viscosity;
  const double tau_trace = tau_bar.trace();
  // D = C + C^T - 2/3 tr C I
  Mat3 D = C + C.transpose();
  D.diagonal().array() -= (2.0 / 3.0) * trace;
  const double J_bar = J_new_bar + K * (2.0 * J - 1.0) * tau_trace + eta * (tau_bar.array() * D.array()).sum();
  // d<tau_bar, eta J D>/dC = eta J (tau_bar + tau_bar^T - 2/3 tr(tau_bar) I)
  Mat3 dC = eta * J * (tau_bar + tau_bar.transpose());
  dC.diagonal().array() -= eta * J * (2.0 / 3.0) * tau_trace;
  // J_new = (1 + dt tr C) J_before
  dC.diagonal().array() += J_bar * dt * J_before;
  C_bar += dC;
  return J_bar * (1.0 + dt * trace);
}

}  // namespace dsb::mpm
