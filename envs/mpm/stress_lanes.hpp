#pragma once
// The solids' stress update in lanes (lane_chunks.hpp SolidChunk): the lanes version of
// substep.cpp's stress phase for solids, i.e. trial_deformation, svd3, solid_update_batch
// (material.cpp) and A = -(4 dt V / dx^2) tau + m C. It follows that scalar code operation for
// operation, in the same order, so each lane gives the bits of the scalar path on its particle
// (tests/test_mpm_lanes.cpp compares them on random states and on whole episodes). Where the
// scalar code is an Eigen expression, the order is Eigen's (eigen_order.hpp).
//
// Include only inside a lanes translation unit (lanes_sse2.cpp, lanes_avx2.cpp), after the
// headers below have been included outside any target pragma.
#include "common/det_math.hpp"
#include "envs/mpm/eigen_order.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/lanes.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/svd3_kernel.hpp"

namespace dsb::mpm {
namespace {

// std::max(x, floor) as the scalar code computes it: x < floor ? floor : x
template <class T>
DSB_LANE_INLINE T max_floor(const T& x, const T& floor) {
  return sel_lt(x, floor, floor, x);
}

// Lanes [o, o + kLanes) of the chunk: F_tmp = (I + dt C) F (Eigen's F + dt * (C * F)), its SVD
// (svd3_kernel, as svd3), F_new = F_tmp for now (elastic), and the logarithms' arguments
// max(sigma, 0.05).
template <class T>
DSB_LANE_INLINE void trial_svd(SolidChunk& c, double dt, int o) {
  const T step(dt);
  T dtC[3][3], F[3][3], a[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      dtC[i][k] = step * load<T>(&c.C[i + 3 * k][o]);
      F[i][k] = load<T>(&c.F[i + 3 * k][o]);
    }
  // F_tmp = F + (dt C) F
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      a[i][j] = F[i][j] + eigen_product_sum(i, dtC[i][0] * F[0][j], dtC[i][1] * F[1][j], dtC[i][2] * F[2][j]);
  T u[3][3], sigma[3], v[3][3];  // u[col][row], v[col][row]
  svd3_kernel(a, u, sigma, v);
  const T floor(kSigmaFloor);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      store(&c.F_new[i + 3 * j][o], a[i][j]);
      store(&c.U[i + 3 * j][o], u[j][i]);
      store(&c.V[i + 3 * j][o], v[j][i]);
    }
    store(&c.sigma[i][o], sigma[i]);
    store(&c.args[i][o], max_floor(sigma[i], floor));
  }
}

// The von Mises return mapping from eps = log max(sigma, 0.05) (in c.values): eps^ = eps - mean,
// |eps^| = sqrt(eps^.eps^ + 1e-8), flow where |eps^| - yield / (2 mu) > 0 (plastic lanes), and
// the flow's targets mean + k eps^, k = yield / (2 mu |eps^|), as the exponentials' arguments.
// Returns true when some lane flows.
template <class T>
DSB_LANE_INLINE bool flow_targets(SolidChunk& c, int o) {
  const T zero(0.0);
  T eps[3];
  for (int a = 0; a < 3; ++a) eps[a] = load<T>(&c.values[a][o]);
  const T mean = ((eps[0] + eps[1]) + eps[2]) / T(3.0);
  T hat[3];
  for (int a = 0; a < 3; ++a) hat[a] = eps[a] - mean;
  // |eps^|: Eigen's squaredNorm, left to right
  const T norm = sqrt_(((hat[0] * hat[0] + hat[1] * hat[1]) + hat[2] * hat[2]) + T(kNormEpsilon));
  const T dgamma = norm - load<T>(&c.threshold[o]);
  const T flow = sel_gt(dgamma, zero, load<T>(&c.plastic[o]), zero);
  const T k = load<T>(&c.yield[o]) / (load<T>(&c.two_mu[o]) * norm);
  for (int a = 0; a < 3; ++a) {
    store(&c.args[a][o], mean + k * hat[a]);
    store(&c.hat[a][o], hat[a]);
  }
  store(&c.flow[o], flow);
  // the tape's k (SolidTape): 1 without flow
  store(&c.k[o], sel_gt(flow, zero, k, T(1.0)));
  store(&c.norm[o], norm);
  return any_gt(flow, zero);
}

// f = exp(target) (flow) or sigma (no flow, or elastic); F_new = U diag(f) V^T where the lane
// flows (F_tmp elsewhere; assigned to F in stress_phase_lanes); the fixed-corotated
// g_i = 2 mu (f_i - 1) f_i + lam J (J - 1), tau = U diag(g) U^T, and A = stress_scale tau + m C.
// (c.values holds the exponentials where some lane of the chunk flows, else the logarithms, which
// no lane then reads.) Without with_F_new (the reverse pass's recomputation) F_new is not formed.
template <class T>
DSB_LANE_INLINE void stress_affine(SolidChunk& c, int o, bool with_F_new) {
  const T zero(0.0), one(1.0);
  const T flow = load<T>(&c.flow[o]);  // 0 on elastic lanes
  T f[3];
  for (int a = 0; a < 3; ++a) {
    f[a] = sel_gt(flow, zero, load<T>(&c.values[a][o]), load<T>(&c.sigma[a][o]));
    store(&c.f[a][o], f[a]);
  }
  T U[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) U[i][k] = load<T>(&c.U[i + 3 * k][o]);
  // F_new = (U diag(f)) V^T where the lane flows
  T Uf[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) Uf[i][k] = U[i][k] * f[k];
  for (int j = 0; j < 3 && with_F_new; ++j) {
    const T v0 = load<T>(&c.V[j][o]), v1 = load<T>(&c.V[j + 3][o]), v2 = load<T>(&c.V[j + 6][o]);
    for (int i = 0; i < 3; ++i) {
      const T x = eigen_assigned_product_sum(Uf[i][0] * v0, Uf[i][1] * v1, Uf[i][2] * v2);
      double* out = &c.F_new[i + 3 * j][o];
      store(out, sel_gt(flow, zero, x, load<T>(out)));
    }
  }
  // g = 2 mu (f - 1) f + lam J (J - 1), J = f0 f1 f2
  const T two_mu = load<T>(&c.two_mu[o]);
  const T J = (f[0] * f[1]) * f[2];
  const T vol = (load<T>(&c.lambda[o]) * J) * (J - one);
  T Ug[3][3];
  for (int k = 0; k < 3; ++k) {
    const T g = ((two_mu * (f[k] - one)) * f[k]) + vol;
    for (int i = 0; i < 3; ++i) Ug[i][k] = U[i][k] * g;
  }
  // tau = (U diag(g)) U^T (solid_stress's return value); A = stress_scale tau + m C
  const T scale = load<T>(&c.stress_scale[o]), mass = load<T>(&c.mass[o]);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const T tau = eigen_product_sum(i, Ug[i][0] * U[j][0], Ug[i][1] * U[j][1], Ug[i][2] * U[j][2]);
      store(&c.A[i + 3 * j][o], scale * tau + mass * load<T>(&c.C[i + 3 * j][o]));
    }
}

// The whole update of a chunk, T = Pack<F2> or Pack<F4>. The logarithms and exponentials of the
// chunk's 24 values go through dm::log_batch / dm::exp_batch (the scalar functions' bits).
// the return mapping and the stress once c.args holds max(sigma, 0.05)
template <class T>
DSB_LANE_INLINE void return_mapping_stress(SolidChunk& c, bool with_F_new) {
  constexpr int W = T::kLanes;
  dm::log_batch(&c.args[0][0], &c.values[0][0], 3 * kLaneChunk);
  bool any_flow = false;
  for (int o = 0; o < kLaneChunk; o += W) any_flow |= flow_targets<T>(c, o);
  if (any_flow) dm::exp_batch(&c.args[0][0], &c.values[0][0], 3 * kLaneChunk);
  for (int o = 0; o < kLaneChunk; o += W) stress_affine<T>(c, o, with_F_new);
}

template <class T>
void solid_stress_chunk(SolidChunk& c, double dt) {
  constexpr int W = T::kLanes;
  static_assert(kLaneChunk % W == 0, "whole packs per chunk");
  for (int o = 0; o < kLaneChunk; o += W) trial_svd<T>(c, dt, o);
  return_mapping_stress<T>(c, true);
}

// The reverse pass's recomputation (substep_adjoint.cpp: solid_update_batch on the SVD that
// restore_svd rebuilt from the tape): from c.U, c.sigma, c.V, the return mapping, f, the tape's
// eps^, |eps^|, k and flow, and A; F_new is not formed.
template <class T>
DSB_LANE_INLINE void solid_stress_restored(SolidChunk& c) {
  constexpr int W = T::kLanes;
  const T floor(kSigmaFloor);
  for (int o = 0; o < kLaneChunk; o += W)
    for (int a = 0; a < 3; ++a) store(&c.args[a][o], max_floor(load<T>(&c.sigma[a][o]), floor));
  return_mapping_stress<T>(c, false);
}

}  // namespace
}  // namespace dsb::mpm
