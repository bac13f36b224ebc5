#pragma once
// P2G and G2P in lanes (lane_chunks.hpp TransferChunk): the lanes version of substep.cpp's p2g
// and g2p. The stencils (kernel.hpp's make_stencil) and P2G's base terms are computed in lanes,
// several particles at a time; the scatter into the grid and the gather from it go particle by
// particle in the scalar loop's order, with a whole grid node in registers (one AVX register, or
// two SSE2 registers, per node). Every operation is the scalar code's, in its order, so each node
// receives the same contributions in the same order and every particle gets the same bits
// (tests/test_mpm_lanes.cpp).
//
// Include only inside a lanes translation unit (see stress_lanes.hpp).
#include "envs/mpm/eigen_order.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/lanes.hpp"

namespace dsb::mpm {
namespace {

// ---- a grid node in registers: 4 doubles (q, m) or 3 (v), lane by lane ----------------------

// floor(x) for |x| < 2^31 (the callers clamp first): truncation, one less where that rounded up
DSB_LANE_INLINE F2 floor_register(F2 x) {
  const F2 t = _mm_cvtepi32_pd(_mm_cvttpd_epi32(x));
  return t > x ? t - F2{1.0, 1.0} : t;
}

template <class R>
struct Node;

// SSE2: (x, y) and (z, m), or (z, 0) for a 3-vector
template <>
struct Node<F2> {
  F2 lo, hi;
  static Node load4(const double* p) { return {load_register<F2>(p), load_register<F2>(p + 2)}; }
  static Node load3(const double* p) { return {load_register<F2>(p), _mm_load_sd(p + 2)}; }
  static Node zero() { return {F2{0.0, 0.0}, F2{0.0, 0.0}}; }
  static Node make(double x, double y, double z, double m) { return {F2{x, y}, F2{z, m}}; }
  void store4(double* p) const {
    std::memcpy(p, &lo, sizeof lo);
    std::memcpy(p + 2, &hi, sizeof hi);
  }
  void store3(double* p) const {
    std::memcpy(p, &lo, sizeof lo);
    _mm_store_sd(p + 2, hi);
  }
  Node operator+(const Node& o) const { return {lo + o.lo, hi + o.hi}; }
  Node operator-(const Node& o) const { return {lo - o.lo, hi - o.hi}; }
  friend Node operator*(double s, const Node& n) {
    const F2 b{s, s};
    return {b * n.lo, b * n.hi};
  }
};

#if defined(DSB_LANES_AVX2)
DSB_LANE_INLINE F4 floor_register(F4 x) { return _mm256_round_pd(x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }

// AVX2: (x, y, z, m), or (x, y, z, 0) for a 3-vector (a masked load reads nothing past it)
template <>
struct Node<F4> {
  F4 q;
  static Node load4(const double* p) { return {load_register<F4>(p)}; }
  static Node load3(const double* p) { return {_mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1))}; }
  static Node zero() { return {F4{0.0, 0.0, 0.0, 0.0}}; }
  static Node make(double x, double y, double z, double m) { return {F4{x, y, z, m}}; }
  void store4(double* p) const { std::memcpy(p, &q, sizeof q); }
  void store3(double* p) const {
    _mm_storeu_pd(p, _mm256_castpd256_pd128(q));
    _mm_store_sd(p + 2, _mm256_extractf128_pd(q, 1));
  }
  Node operator+(const Node& o) const { return {q + o.q}; }
  Node operator-(const Node& o) const { return {q - o.q}; }
  friend Node operator*(double s, const Node& n) { return {F4{s, s, s, s} * n.q}; }
};
#endif

template <class R>
DSB_LANE_INLINE Pack<R> floor_(const Pack<R>& x) {
  return {floor_register(x.a), floor_register(x.b)};
}

// ---- stencils -----------------------------------------------------------------------------------

// make_stencil of lanes [o, o + kLanes): per axis b = floor(x / dx - 1/2) clamped to
// [-pad, n - 3 - pad] (NaN to -pad), f = x / dx - b, the weights and their derivatives. floor
// runs on x / dx - 1/2 clamped to [low - 1, top + 1] first, which changes no clamped b and keeps
// it within the range of a 32-bit truncation.
template <class T, class Chunk>
DSB_LANE_INLINE void stencil_lanes(Chunk& c, const TransferGrid& g, int o) {
  const T inv_dx(g.inv_dx), one(1.0), half(0.5);
  for (int a = 0; a < 3; ++a) {
    const T scaled = load<T>(&c.x[a][o]) * inv_dx;
    const T low(g.stencil_low[a]), top(g.stencil_top[a]);
    const T below = low - one, above = top + one;
    const T y = scaled - half;
    const T b0 = floor_(sel_ge(y, below, sel_gt(y, above, above, y), below));
    // b = !(b >= low) ? low : (b > top ? top : b)
    const T b = sel_ge(b0, low, sel_gt(b0, top, top, b0), low);
    const T f = scaled - b;
    const T d0 = T(1.5) - f, d1 = f - one, d2 = f - half;
    store(&c.base[a][o], b);
    store(&c.fx[a][o], f);
    store(&c.w[a][0][o], (half * d0) * d0);
    store(&c.w[a][1][o], T(0.75) - d1 * d1);
    store(&c.w[a][2][o], (half * d2) * d2);
    store(&c.dw[a][0][o], (-d0) * inv_dx);
    store(&c.dw[a][1][o], (T(-2.0) * d1) * inv_dx);
    store(&c.dw[a][2][o], d2 * inv_dx);
  }
}

// the node index of a particle's stencil corner (offsets 0, 0, 0)
template <class Chunk>
DSB_LANE_INLINE int corner_node(const Chunk& c, const TransferGrid& g, int l, int& b2) {
  const int b0 = static_cast<int>(c.base[0][l]) + g.pad, b1 = static_cast<int>(c.base[1][l]) + g.pad;
  b2 = static_cast<int>(c.base[2][l]) + g.pad;
  return (b0 * g.n1 + b1) * g.n2 + b2;
}

// node += d for a node of K doubles (4: (q, m), 3: a velocity or its adjoint)
template <int K, class R>
DSB_LANE_INLINE void add_to_node(double* node, const Node<R>& d) {
  static_assert(K == 3 || K == 4);
  if constexpr (K == 4)
    (Node<R>::load4(node) + d).store4(node);
  else
    (Node<R>::load3(node) + d).store3(node);
}

// node += w (t + i a0 + j a1 + k a2) for the 27 nodes (i, j, k) of particle l's stencil, K doubles
// a node (4: P2G's (q, m), 3: G2P^T's velocity adjoints): kernel.hpp's scatter_affine in its order
template <int K, class R>
DSB_LANE_INLINE void scatter_affine_lanes(const TransferChunk& c, const TransferGrid& g, int l, const Node<R>& t,
                                          const Node<R>& a0, const Node<R>& a1, const Node<R>& a2, double* nodes) {
  using N = Node<R>;
  int b2;
  const int corner = corner_node(c, g, l, b2);
  const double wz0 = c.w[2][0][l], wz1 = c.w[2][1][l], wz2 = c.w[2][2][l];
  for (int i = 0; i < 3; ++i) {
    const N ti = t + static_cast<double>(i) * a0;
    for (int j = 0; j < 3; ++j) {
      const N tij = ti + static_cast<double>(j) * a1;
      const double wij = c.w[0][i][l] * c.w[1][j][l];
      double* node = nodes + K * (corner + (i * g.n1 + j) * g.n2);
      add_to_node<K>(node, (wij * wz0) * tij);
      add_to_node<K>(node + K, (wij * wz1) * (tij + a2));
      add_to_node<K>(node + 2 * K, (wij * wz2) * (tij + 2.0 * a2));
    }
  }
}

// ---- P2G ----------------------------------------------------------------------------------------

// P2G's base term m v - dx (A fx) (Eigen: (dx A) fx) and dx A, lanes [o, o + kLanes)
template <class T>
DSB_LANE_INLINE void p2g_terms(TransferChunk& c, const TransferGrid& g, int o) {
  const T dx(g.dx), mass = load<T>(&c.mass[o]);
  T fx[3], dA[3][3];
  for (int k = 0; k < 3; ++k) fx[k] = load<T>(&c.fx[k][o]);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      dA[i][k] = dx * load<T>(&c.A[i + 3 * k][o]);
      store(&c.dxA[i + 3 * k][o], dA[i][k]);
    }
  for (int i = 0; i < 3; ++i)
    store(&c.base_term[i][o],
          mass * load<T>(&c.v[i][o]) - eigen_product_sum(i, dA[i][0] * fx[0], dA[i][1] * fx[1], dA[i][2] * fx[2]));
}

// (q_i, m_i) += w (m v + A dpos, m) for the 27 nodes of particle l: with t = (base term, m) and
// a_k = (dx A e_k, 0), node (i, j, k) gets w (t + i a_0 + j a_1 + k a_2), summed as substep.cpp's p2g
template <class R>
DSB_LANE_INLINE void p2g_scatter(const TransferChunk& c, const TransferGrid& g, int l, double* mq) {
  using N = Node<R>;
  const N base = N::make(c.base_term[0][l], c.base_term[1][l], c.base_term[2][l], c.mass[l]);
  const N a0 = N::make(c.dxA[0][l], c.dxA[1][l], c.dxA[2][l], 0.0);
  const N a1 = N::make(c.dxA[3][l], c.dxA[4][l], c.dxA[5][l], 0.0);
  const N a2 = N::make(c.dxA[6][l], c.dxA[7][l], c.dxA[8][l], 0.0);
  scatter_affine_lanes<4>(c, g, l, base, a0, a1, a2, mq);
}

template <class T>
void p2g_chunk(TransferChunk& c, const TransferGrid& g, double* mq) {
  constexpr int W = T::kLanes;
  for (int o = 0; o < kLaneChunk; o += W) {
    stencil_lanes<T>(c, g, o);
    p2g_terms<T>(c, g, o);
  }
  for (int l = 0; l < c.count; ++l) p2g_scatter<decltype(T::a)>(c, g, l, mq);
}

// ---- G2P ----------------------------------------------------------------------------------------

// v = sum w v_i and B = sum w v_i o^T over the 27 nodes of particle l (the z sums first, as
// substep.cpp's g2p), then C = (4 / dx) (B - v fx^T)
template <class R>
DSB_LANE_INLINE void g2p_gather(TransferChunk& c, const TransferGrid& g, int l, const double* gv) {
  using N = Node<R>;
  int b2;
  const int corner = corner_node(c, g, l, b2);
  const double wz0 = c.w[2][0][l], wz1 = c.w[2][1][l], wz2 = c.w[2][2][l];
  N v = N::zero(), B0 = N::zero(), B1 = N::zero(), B2 = N::zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double* node = gv + 3 * (corner + (i * g.n1 + j) * g.n2);
      const N v0 = N::load3(node), v1 = N::load3(node + 3), v2 = N::load3(node + 6);
      const N vz = (wz0 * v0 + wz1 * v1) + wz2 * v2;
      const N vzk = wz1 * v1 + (2.0 * wz2) * v2;
      const double wij = c.w[0][i][l] * c.w[1][j][l];
      v = v + wij * vz;
      B0 = B0 + (wij * static_cast<double>(i)) * vz;
      B1 = B1 + (wij * static_cast<double>(j)) * vz;
      B2 = B2 + wij * vzk;
    }
  const double scale = 4.0 * g.inv_dx;
  double column[3][4];
  (scale * (B0 - c.fx[0][l] * v)).store3(column[0]);
  (scale * (B1 - c.fx[1][l] * v)).store3(column[1]);
  (scale * (B2 - c.fx[2][l] * v)).store3(column[2]);
  double vel[4];
  v.store3(vel);
  for (int r = 0; r < 3; ++r) {
    c.v_new[r][l] = vel[r];
    for (int k = 0; k < 3; ++k) c.C_new[r + 3 * k][l] = column[k][r];
  }
}

// x + dt v, clamped to the domain (std::min(std::max(x, lo), hi)), lanes [o, o + kLanes)
template <class T>
DSB_LANE_INLINE void advect_lanes(TransferChunk& c, const TransferGrid& g, int o) {
  const T dt(g.dt), lo(g.clamp_low);
  for (int a = 0; a < 3; ++a) {
    const T x = load<T>(&c.x[a][o]) + dt * load<T>(&c.v_new[a][o]);
    const T hi(g.clamp_high[a]);
    const T m = sel_lt(x, lo, lo, x);
    store(&c.x_new[a][o], sel_lt(hi, m, hi, m));
  }
}

template <class T>
void g2p_chunk(TransferChunk& c, const TransferGrid& g, const double* gv) {
  constexpr int W = T::kLanes;
  for (int o = 0; o < kLaneChunk; o += W) stencil_lanes<T>(c, g, o);
  for (int l = 0; l < c.count; ++l) g2p_gather<decltype(T::a)>(c, g, l, gv);
  for (int l = c.count; l < kLaneChunk; ++l)
    for (int a = 0; a < 3; ++a) c.v_new[a][l] = 0.0;
  for (int o = 0; o < kLaneChunk; o += W) advect_lanes<T>(c, g, o);
}

}  // namespace
}  // namespace dsb::mpm
