#pragma once
// The reverse of one substep for the solids of a chunk, in lanes (lane_chunks.hpp
// SolidAdjointChunk): the lanes version of substep_adjoint.cpp's particle_adjoint for solids and
// of material.cpp's solid_update_adjoint, plastic_derivatives, corotated_diagonal and svd3.cpp's
// iso_uu_adjoint and iso_uv_adjoint. Every operation is the scalar code's, in its order; where the
// scalar code branches (flow or not, sigma at the floor of 0.05 or not, the divided differences'
// series or quotient), both sides are computed and the lane takes the scalar code's side. Eigen's
// product orders (eigen_order.hpp, measured in each of these statements' forms):
//   A^T x (matrix-vector, transposed matrix): (t0 + t1) + t2 in every row;
//   X Y, (X Y) Z, U H V^T (constructed or returned): rows 0, 1 (t0 + t1) + t2, row 2 t0 + (t1 + t2);
//   U^T X (the inner product of U^T X V): (t0 + t1) + t2 in every row;
//   C_bar += dt (X F^T): (dt X) F^T with rows 0, 1 left to right and row 2 split;
//   F_bar = X + dt (C^T X): (dt C^T) X with every row left to right.
//
// Include only inside a lanes translation unit (see stress_lanes.hpp).
#include "envs/mpm/adjoint_lanes.hpp"
#include "envs/mpm/eigen_order.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/lanes.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/stress_lanes.hpp"
#include "envs/mpm/svd3.hpp"
#include "envs/mpm/transfer_lanes.hpp"

namespace dsb::mpm {
namespace {

template <class T>
DSB_LANE_INLINE T left_sum(const T& t0, const T& t1, const T& t2) {
  return (t0 + t1) + t2;
}

// x with |x| raised to at least floor, its sign kept (0 counts as positive): svd3.cpp's
// away_from_zero
template <class T>
DSB_LANE_INLINE T away_from_zero(const T& x, const T& floor) {
  return sel_ge(abs_(x), floor, x, sel_lt(x, T(0.0), -floor, floor));
}

// ((1 + r)^k - 1) / r by its binomial series to r^5 (material.cpp's power_quotient_series)
template <class T>
DSB_LANE_INLINE T power_quotient_series(const T& k, const T& r) {
  T term = k, sum = k;
  for (int n = 1; n <= 5; ++n) {
    term = term * (((k - T(static_cast<double>(n))) / T(static_cast<double>(n + 1))) * r);
    sum = sum + term;
  }
  return sum;
}

// (U^T X) Y for the inner product of U^T X V and U^T X U: U^T X left to right in every row, then
// the product with Y as eigen_product_sum
template <class T>
DSB_LANE_INLINE void transposed_chain(const T (&U)[3][3], const T (&X)[3][3], const T (&Y)[3][3], T (&out)[3][3]) {
  T P[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) P[i][j] = left_sum(U[0][i] * X[0][j], U[1][i] * X[1][j], U[2][i] * X[2][j]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      out[i][j] = eigen_product_sum(i, P[i][0] * Y[0][j], P[i][1] * Y[1][j], P[i][2] * Y[2][j]);
}

// (U H) V^T, both products as eigen_product_sum (iso adjoints' return value)
template <class T>
DSB_LANE_INLINE void back_to_F(const T (&U)[3][3], const T (&H)[3][3], const T (&V)[3][3], T (&out)[3][3]) {
  T Q[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Q[i][j] = eigen_product_sum(i, U[i][0] * H[0][j], U[i][1] * H[1][j], U[i][2] * H[2][j]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      out[i][j] = eigen_product_sum(i, Q[i][0] * V[j][0], Q[i][1] * V[j][1], Q[i][2] * V[j][2]);
}

// A matrix of the chunk (column-major element i + 3 j) into [row][col] lanes
template <class T>
DSB_LANE_INLINE void load_matrix(const double (&m)[9][kLaneChunk], int o, T (&out)[3][3]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[i][j] = load<T>(&m[i + 3 * j][o]);
}

// ---- the gather's terms -------------------------------------------------------------------------

// t0 = m v - dx A fx ((dx A) fx), dx A, C_s = (4 / dx^2) dL/dC', dx C_s, u0 = v_bar - dx C_s fx
template <class T>
DSB_LANE_INLINE void gather_terms(SolidAdjointChunk& c, const TransferGrid& g, int o) {
  const T dx(g.dx), cs_scale(4.0 * g.inv_dx * g.inv_dx), mass = load<T>(&c.stress.mass[o]);
  T fx[3], dA[3][3], dCs[3][3];
  for (int k = 0; k < 3; ++k) fx[k] = load<T>(&c.fx[k][o]);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      dA[i][k] = dx * load<T>(&c.stress.A[i + 3 * k][o]);
      store(&c.dxA[i + 3 * k][o], dA[i][k]);
      const T Cs = cs_scale * load<T>(&c.adj_C[i + 3 * k][o]);
      store(&c.Cs[i + 3 * k][o], Cs);
      dCs[i][k] = dx * Cs;
      store(&c.dxCs[i + 3 * k][o], dCs[i][k]);
    }
  for (int i = 0; i < 3; ++i) {
    store(&c.t0[i][o],
          mass * load<T>(&c.v[i][o]) - eigen_product_sum(i, dA[i][0] * fx[0], dA[i][1] * fx[1], dA[i][2] * fx[2]));
    store(&c.u0[i][o],
          load<T>(&c.adv_v[i][o]) - eigen_product_sum(i, dCs[i][0] * fx[0], dCs[i][1] * fx[1], dCs[i][2] * fx[2]));
  }
}

// particle_adjoint's node sums of lane l (adjoint_lanes.hpp's p2g_adjoint_gather)
template <class R>
DSB_LANE_INLINE void gather_lane(SolidAdjointChunk& c, const TransferGrid& g, int l, const double* qmb,
                                 const double* gv) {
  GatherTerms terms;
  int b2;
  terms.corner = corner_node(c, g, l, b2);
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 3; ++k) {
      terms.w[a][k] = c.w[a][k][l];
      terms.dw[a][k] = c.dw[a][k][l];
      terms.ad[k][a] = c.dxA[a + 3 * k][l];
      terms.cd[k][a] = c.dxCs[a + 3 * k][l];
    }
  for (int a = 0; a < 3; ++a) {
    terms.t0[a] = c.t0[a][l];
    terms.u0[a] = c.u0[a][l];
  }
  terms.t0[3] = c.stress.mass[l];
  for (int k = 0; k < 3; ++k) terms.ad[k][3] = 0.0;
  GatherSums sums;
  p2g_adjoint_gather<R>(terms, g, qmb, gv, sums);
  for (int a = 0; a < 3; ++a) {
    c.xg[a][l] = sums.x_bar[a];
    c.sum_wq[a][l] = sums.sum_wq[a];
  }
  for (int e = 0; e < 9; ++e) c.Mq[e][l] = sums.Mq[e];
}

// ---- after the gather ---------------------------------------------------------------------------

// x_bar, v_bar, C_bar of particle_adjoint, then solid_update_adjoint, lanes [o, o + kLanes)
template <class T>
DSB_LANE_INLINE void solid_adjoint_tail(SolidAdjointChunk& c, const TransferGrid& g, int o) {
  const SolidChunk& s = c.stress;
  const T zero(0.0), one(1.0), half(0.5), floor(kSigmaFloor), third(1.0 / 3.0);
  const T dx(g.dx), dt(g.dt), mass = load<T>(&s.mass[o]), scale = load<T>(&s.stress_scale[o]);
  T A[3][3], Cs[3][3], Mq[3][3], fx[3], sum_wq[3], v_new[3];
  load_matrix(s.A, o, A);
  load_matrix(c.Cs, o, Cs);
  load_matrix(c.Mq, o, Mq);
  for (int a = 0; a < 3; ++a) {
    fx[a] = load<T>(&c.fx[a][o]);
    sum_wq[a] = load<T>(&c.sum_wq[a][o]);
    v_new[a] = load<T>(&c.v_new[a][o]);
  }
  // x_bar += adv.x_bar - C_s^T v' - A^T sum_wq; v_bar = m sum_wq
  for (int i = 0; i < 3; ++i) {
    const T cv = left_sum(Cs[0][i] * v_new[0], Cs[1][i] * v_new[1], Cs[2][i] * v_new[2]);
    const T aq = left_sum(A[0][i] * sum_wq[0], A[1][i] * sum_wq[1], A[2][i] * sum_wq[2]);
    store(&c.out_x[i][o], load<T>(&c.xg[i][o]) + ((load<T>(&c.adv_x[i][o]) - cv) - aq));
    store(&c.out_v[i][o], mass * sum_wq[i]);
  }
  // A_bar = dx (Mq - sum_wq fx^T); tau_bar = -k A_bar; C_bar = m A_bar
  T tau_bar[3][3], C_bar[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T A_bar = dx * (Mq[i][j] - sum_wq[i] * fx[j]);
      tau_bar[i][j] = scale * A_bar;
      C_bar[i][j] = mass * A_bar;
    }

  // ---- solid_update_adjoint
  const T flow = load<T>(&s.flow[o]);  // 0 on elastic lanes
  const T two_mu = load<T>(&s.two_mu[o]), lam = load<T>(&s.lambda[o]);
  const T k = load<T>(&s.k[o]), norm = load<T>(&s.norm[o]);
  T sigma[3], f[3], hat[3], inv[3];
  for (int a = 0; a < 3; ++a) {
    sigma[a] = load<T>(&s.sigma[a][o]);
    f[a] = load<T>(&s.f[a][o]);
    hat[a] = load<T>(&s.hat[a][o]);
    inv[a] = sel_gt(sigma[a], floor, one / sigma[a], zero);
  }
  T U[3][3], V[3][3];
  load_matrix(s.U, o, U);
  load_matrix(s.V, o, V);
  // plastic_derivatives: dfds(i, j) = d f_i / d sigma_j and the divided differences dd(i, j);
  // the identity and ones without flow (f = sigma)
  const T n2 = norm * norm;
  T dfds[3][3], dd[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T delta(i == j ? 1.0 : 0.0);
      const T de = (third + k * (delta - third)) - ((k * hat[i]) * hat[j]) / n2;
      const T with_flow = (f[i] * de) * inv[j];
      dfds[i][j] = sel_gt(flow, zero, with_flow, delta);
      if (i == j) {
        dd[i][j] = zero;
        continue;
      }
      const T quotient = (f[i] - f[j]) / (sigma[i] - sigma[j]);
      const T r = (sigma[i] - sigma[j]) / sigma[j];
      const T series = (f[j] / sigma[j]) * power_quotient_series(k, r);
      const T both = sel_le(abs_(r), T(1e-3), series, quotient);
      // both above the floor: both; both at it: 0; one at it: the quotient
      const T above_i = sel_gt(sigma[i], floor, one, zero), above_j = sel_gt(sigma[j], floor, one, zero);
      const T above =
          sel_gt(above_i, zero, sel_gt(above_j, zero, both, quotient), sel_gt(above_j, zero, quotient, zero));
      dd[i][j] = sel_gt(flow, zero, above, one);
    }
  // corotated_diagonal's dg/df, then dg/dsigma = dg/df df/dsigma and ddg = 2 mu (f_i + f_j - 1) dd
  const T J = (f[0] * f[1]) * f[2];
  const T J_over[3] = {f[1] * f[2], f[0] * f[2], f[0] * f[1]};
  const T vol_slope = lam * (T(2.0) * J - one);
  T dgdf[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) dgdf[i][j] = (i == j ? two_mu * (T(2.0) * f[i] - one) : zero) + vol_slope * J_over[j];
  T dgds[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      dgds[i][j] = eigen_product_sum(i, dgdf[i][0] * dfds[0][j], dgdf[i][1] * dfds[1][j], dgdf[i][2] * dfds[2][j]);
  const T iso_floor(kIsoDenominatorFloor);
  // iso_uu_adjoint: S = sym(U^T tau_bar U); H_ii = sum_j dgds(j, i) S_jj; for i < j
  // w = 2 S_ij ddg(i, j) / (sigma_i + sigma_j), H_ij = w sigma_j, H_ji = w sigma_i; U H V^T
  T M[3][3], H[3][3], X[3][3];
  transposed_chain(U, tau_bar, U, M);
  T S[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) S[i][j] = half * (M[i][j] + M[j][i]);
  for (int i = 0; i < 3; ++i) H[i][i] = left_sum(dgds[0][i] * S[0][0], dgds[1][i] * S[1][1], dgds[2][i] * S[2][2]);
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      const T ddg = (two_mu * ((f[i] + f[j]) - one)) * dd[i][j];
      const T e = ddg / away_from_zero(sigma[i] + sigma[j], iso_floor);
      const T w = (T(2.0) * S[i][j]) * e;
      H[i][j] = w * sigma[j];
      H[j][i] = w * sigma[i];
    }
  back_to_F(U, H, V, X);
  // iso_uv_adjoint (flow): G = U^T F_new_bar V; H_ii = sum_j dfds(j, i) G_jj; H_ij =
  // (a + b)/2 G_ij + (a - b)/2 G_ji, a = dd(i, j), b = (f_i + f_j) / (sigma_i + sigma_j); U H V^T.
  // Lanes without flow add F_new_bar itself.
  T F_new_bar[3][3], G[3][3], Y[3][3];
  load_matrix(c.adj_F, o, F_new_bar);
  transposed_chain(U, F_new_bar, V, G);
  for (int i = 0; i < 3; ++i) {
    H[i][i] = left_sum(dfds[0][i] * G[0][0], dfds[1][i] * G[1][1], dfds[2][i] * G[2][2]);
    for (int j = 0; j < 3; ++j) {
      if (j == i) continue;
      const T a = dd[i][j];
      const T b = (f[i] + f[j]) / away_from_zero(sigma[i] + sigma[j], iso_floor);
      H[i][j] = (half * (a + b)) * G[i][j] + (half * (a - b)) * G[j][i];
    }
  }
  back_to_F(U, H, V, Y);
  T F_tmp_bar[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F_tmp_bar[i][j] = X[i][j] + sel_gt(flow, zero, Y[i][j], F_new_bar[i][j]);
  // F_tmp = (I + dt C) F: C_bar += (dt F_tmp_bar) F^T, F_bar = F_tmp_bar + (dt C^T) F_tmp_bar
  T C[3][3], F[3][3];
  load_matrix(s.C, o, C);
  load_matrix(s.F, o, F);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T t0 = (dt * F_tmp_bar[i][0]) * F[j][0], t1 = (dt * F_tmp_bar[i][1]) * F[j][1],
              t2 = (dt * F_tmp_bar[i][2]) * F[j][2];
      store(&c.out_C[i + 3 * j][o], C_bar[i][j] + eigen_product_sum(i, t0, t1, t2));
      const T u0 = (dt * C[0][i]) * F_tmp_bar[0][j], u1 = (dt * C[1][i]) * F_tmp_bar[1][j],
              u2 = (dt * C[2][i]) * F_tmp_bar[2][j];
      store(&c.out_F[i + 3 * j][o], F_tmp_bar[i][j] + left_sum(u0, u1, u2));
    }
}

template <class T>
void solid_adjoint_chunk(SolidAdjointChunk& c, const TransferGrid& g, const double* qmb, const double* gv) {
  constexpr int W = T::kLanes;
  solid_stress_restored<T>(c.stress);
  for (int o = 0; o < kLaneChunk; o += W) {
    stencil_lanes<T>(c, g, o);
    gather_terms<T>(c, g, o);
  }
  for (int l = 0; l < c.count; ++l) gather_lane<decltype(T::a)>(c, g, l, qmb, gv);
  for (int l = c.count; l < kLaneChunk; ++l) {  // padding: finite sums
    for (int a = 0; a < 3; ++a) c.xg[a][l] = c.sum_wq[a][l] = 0.0;
    for (int e = 0; e < 9; ++e) c.Mq[e][l] = 0.0;
  }
  for (int o = 0; o < kLaneChunk; o += W) solid_adjoint_tail<T>(c, g, o);
}

}  // namespace
}  // namespace dsb::mpm
