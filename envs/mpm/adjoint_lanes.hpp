#pragma once
// The reverse pass's transfers in lanes: G2P^T (substep_adjoint.cpp's g2p_adjoint: the
// advection's adjoint, then each particle's scatter into the grid's velocity adjoints in the
// scalar loop's order) and the P2G^T gather of particle_adjoint (one particle's sums over its 27
// nodes, a whole node in registers). Every operation is the scalar code's, in its order, Eigen's
// reductions included (eigen_order.hpp, dot4 and dot3 below), so the bits are the scalar path's
// (tests/test_mpm_lanes.cpp).
//
// Include only inside a lanes translation unit (see stress_lanes.hpp).
#include "envs/mpm/eigen_order.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/lanes.hpp"
#include "envs/mpm/transfer_lanes.hpp"

namespace dsb::mpm {
namespace {

// ---- G2P^T --------------------------------------------------------------------------------------

// The advection's adjoint (x' = clamp(x + dt v'): x_bar = x'_bar where not clamped, else 0;
// v_bar = v'_bar + dt x_bar), C_s = (4 / dx) C'_bar and the scatter's base term v_bar - C_s fx,
// lanes [o, o + kLanes)
template <class T>
DSB_LANE_INLINE void g2p_adjoint_terms(TransferChunk& c, const TransferGrid& g, int o) {
  const T dt(g.dt), lo(g.clamp_low), zero(0.0), scale(4.0 * g.inv_dx);
  T v_bar[3];
  for (int a = 0; a < 3; ++a) {
    const T x_new = load<T>(&c.x[a][o]) + dt * load<T>(&c.v_new[a][o]);
    const T hi(g.clamp_high[a]);
    const T x_bar = sel_ge(x_new, lo, sel_le(x_new, hi, load<T>(&c.adj_x[a][o]), zero), zero);
    v_bar[a] = load<T>(&c.adj_v[a][o]) + dt * x_bar;
    store(&c.x_bar[a][o], x_bar);
    store(&c.v_bar[a][o], v_bar[a]);
  }
  T Cs[3][3], fx[3];
  for (int k = 0; k < 3; ++k) fx[k] = load<T>(&c.fx[k][o]);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      Cs[i][k] = scale * load<T>(&c.adj_C[i + 3 * k][o]);
      store(&c.Cs[i + 3 * k][o], Cs[i][k]);
    }
  for (int i = 0; i < 3; ++i)
    store(&c.base_term[i][o], v_bar[i] - eigen_product_sum(i, Cs[i][0] * fx[0], Cs[i][1] * fx[1], Cs[i][2] * fx[2]));
}

// node v_bar += w (base + C_s o) for the 27 nodes of particle l
template <class R>
DSB_LANE_INLINE void g2p_adjoint_scatter(const TransferChunk& c, const TransferGrid& g, int l, double* vb) {
  using N = Node<R>;
  const N base = N::make(c.base_term[0][l], c.base_term[1][l], c.base_term[2][l], 0.0);
  const N c0 = N::make(c.Cs[0][l], c.Cs[1][l], c.Cs[2][l], 0.0);
  const N c1 = N::make(c.Cs[3][l], c.Cs[4][l], c.Cs[5][l], 0.0);
  const N c2 = N::make(c.Cs[6][l], c.Cs[7][l], c.Cs[8][l], 0.0);
  scatter_affine_lanes<3>(c, g, l, base, c0, c1, c2, vb);
}

template <class T>
void g2p_adjoint_chunk(TransferChunk& c, const TransferGrid& g, double* vb) {
  constexpr int W = T::kLanes;
  for (int o = 0; o < kLaneChunk; o += W) {
    stencil_lanes<T>(c, g, o);
    g2p_adjoint_terms<T>(c, g, o);
  }
  for (int l = 0; l < c.count; ++l) g2p_adjoint_scatter<decltype(T::a)>(c, g, l, vb);
}

// ---- P2G^T gather ---------------------------------------------------------------------------------

// Eigen's dot products in the portable build: a 4-vector as two SSE2 packets added, then the
// packet's halves, (p0 + p2) + (p1 + p3); a 3-vector as one packet and the last entry, (p0 + p1) + p2.
DSB_LANE_INLINE double dot4(const Node<F2>& a, const Node<F2>& b) {
  const F2 s = a.lo * b.lo + a.hi * b.hi;
  return s[0] + s[1];
}
DSB_LANE_INLINE double dot3(const Node<F2>& a, const Node<F2>& b) {
  const F2 lo = a.lo * b.lo;
  return (lo[0] + lo[1]) + a.hi[0] * b.hi[0];
}
#if defined(DSB_LANES_AVX2)
DSB_LANE_INLINE double dot4(const Node<F4>& a, const Node<F4>& b) {
  const F4 p = a.q * b.q;
  const F2 s = _mm256_castpd256_pd128(p) + _mm256_extractf128_pd(p, 1);
  return s[0] + s[1];
}
DSB_LANE_INLINE double dot3(const Node<F4>& a, const Node<F4>& b) {
  const F4 p = a.q * b.q;
  return (p[0] + p[1]) + p[2];
}
#endif

// particle_adjoint's loop over the 27 nodes: per node n (offset o), sc = (q_bar, m_bar) . t_n +
// v_n . u_n; the z sums first (S0 = sum w_z sc, S1 = sum w_z' sc, Q0 = sum w_z q_bar,
// Qk = sum k w_z q_bar), then x_bar += (w_x' w_y S0, w_x w_y' S0, w_x w_y S1), sum_wq += w_xy Q0,
// Mq += w_xy (i Q0, j Q0, Qk)
template <class R>
void p2g_adjoint_gather(const GatherTerms& in, const TransferGrid& g, const double* qmb, const double* gv,
                        GatherSums& out) {
  using N = Node<R>;
  const N t0 = N::load4(in.t0), ad0 = N::load4(in.ad[0]), ad1 = N::load4(in.ad[1]), ad2 = N::load4(in.ad[2]);
  const N u0 = N::make(in.u0[0], in.u0[1], in.u0[2], 0.0);
  const N cd0 = N::make(in.cd[0][0], in.cd[0][1], in.cd[0][2], 0.0);
  const N cd1 = N::make(in.cd[1][0], in.cd[1][1], in.cd[1][2], 0.0);
  const N cd2 = N::make(in.cd[2][0], in.cd[2][1], in.cd[2][2], 0.0);
  double xb0 = 0.0, xb1 = 0.0, xb2 = 0.0;
  N sum_wq = N::zero(), M0 = N::zero(), M1 = N::zero(), M2 = N::zero();
  for (int i = 0; i < 3; ++i) {
    const N ti = t0 + static_cast<double>(i) * ad0;
    const N ui = u0 + static_cast<double>(i) * cd0;
    for (int j = 0; j < 3; ++j) {
      const N tij = ti + static_cast<double>(j) * ad1;
      const N uij = ui + static_cast<double>(j) * cd1;
      const int row = in.corner + (i * g.n1 + j) * g.n2;
      double S0 = 0.0, S1 = 0.0;
      N Q0 = N::zero(), Qk = N::zero();
      for (int k = 0; k < 3; ++k) {
        const N q = N::load4(qmb + 4 * (row + k));
        const double sc = dot4(q, tij + static_cast<double>(k) * ad2) +
            dot3(N::load3(gv + 3 * (row + k)), uij + static_cast<double>(k) * cd2);
        S0 += in.w[2][k] * sc;
        S1 += in.dw[2][k] * sc;
        const N wq = in.w[2][k] * q;  // its mass entry is not read
        Q0 = Q0 + wq;
        Qk = Qk + static_cast<double>(k) * wq;
      }
      const double wxy = in.w[0][i] * in.w[1][j];
      xb0 += in.dw[0][i] * in.w[1][j] * S0;
      xb1 += in.w[0][i] * in.dw[1][j] * S0;
      xb2 += wxy * S1;
      sum_wq = sum_wq + wxy * Q0;
      M0 = M0 + (wxy * static_cast<double>(i)) * Q0;
      M1 = M1 + (wxy * static_cast<double>(j)) * Q0;
      M2 = M2 + wxy * Qk;
    }
  }
  out.x_bar[0] = xb0;
  out.x_bar[1] = xb1;
  out.x_bar[2] = xb2;
  double column[4];
  sum_wq.store4(column);
  for (int r = 0; r < 3; ++r) out.sum_wq[r] = column[r];
  const N* M[3] = {&M0, &M1, &M2};
  for (int k = 0; k < 3; ++k) {
    M[k]->store4(column);
    for (int r = 0; r < 3; ++r) out.Mq[r + 3 * k] = column[r];
  }
}

}  // namespace
}  // namespace dsb::mpm
