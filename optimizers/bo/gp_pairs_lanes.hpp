#pragma once
// The lanes kernels of gp_pairs.hpp, written once over a GCC vector type V of L doubles and
// compiled twice: gp_pairs_sse2.cpp (V of 2 doubles) and gp_pairs_avx.cpp (V of 4, inside
// `#pragma GCC target("avx")`), each file handing out its copy as a LaneKernels (gp_pairs.cpp picks
// one per path). Everything else sits in an anonymous namespace, so the two copies never meet at
// link time. Loads and stores are unaligned moves.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

namespace dsb::gp_pairs {

// gp_pairs.hpp's two loops in one register width, as gp_pairs.cpp calls them
struct LaneKernels {
  void (*squared_distances)(const double* Xt, int n, int d, double* R);
  void (*ard_gradient)(const double* Xs, int n, int d, const double* C, double* gl);
};
const LaneKernels& sse2_kernels();  // gp_pairs_sse2.cpp
const LaneKernels& avx_kernels();   // gp_pairs_avx.cpp: call only on a CPU with AVX

namespace {

// dimensions per pass over the points: a chunk of Xt (n x 32 doubles, 256 KB at n = 1,000) or of
// Xs (32 doubles per point) stays in the L2 cache while every pair passes over it
constexpr int kDimChunk = 32;
// registers of pairs per distance tile: four independent addition chains hide the adder's latency
constexpr int kTileRegisters = 4;

template <class V>
[[gnu::always_inline]] inline V load(const double* p) {
  typedef V Unaligned __attribute__((aligned(alignof(double))));
  return *reinterpret_cast<const Unaligned*>(p);
}
template <class V>
[[gnu::always_inline]] inline void store(double* p, V v) {
  typedef V Unaligned __attribute__((aligned(alignof(double))));
  *reinterpret_cast<Unaligned*>(p) = v;
}

// out[k] (k < kTileRegisters L) continues the distance sums of points a + k from b over the
// dimensions [i0, i1); first: the sums start at 0.0, else from out
template <class V>
[[gnu::always_inline]] inline void distance_tile(const double* Xt, std::size_t ld, int i0, int i1, int b, int a,
                                                 bool first, double* out) {
  constexpr int L = static_cast<int>(sizeof(V) / sizeof(double));
  V s0 = first ? V{} : load<V>(out), s1 = first ? V{} : load<V>(out + L);
  V s2 = first ? V{} : load<V>(out + 2 * L), s3 = first ? V{} : load<V>(out + 3 * L);
  for (int i = i0; i < i1; ++i) {
    const double* col = Xt + static_cast<std::size_t>(i) * ld + a;
    const double xb = Xt[static_cast<std::size_t>(i) * ld + b];
    const V t0 = load<V>(col) - xb, t1 = load<V>(col + L) - xb;
    const V t2 = load<V>(col + 2 * L) - xb, t3 = load<V>(col + 3 * L) - xb;
    s0 += t0 * t0;
    s1 += t1 * t1;
    s2 += t2 * t2;
    s3 += t3 * t3;
  }
  store(out, s0);
  store(out + L, s1);
  store(out + 2 * L, s2);
  store(out + 3 * L, s3);
}

template <class V>
void squared_distances_lanes(const double* Xt, int n, int d, double* R) {
  constexpr int L = static_cast<int>(sizeof(V) / sizeof(double));
  constexpr int kTile = kTileRegisters * L;
  const std::size_t ld = static_cast<std::size_t>(n);
  for (int i0 = 0; i0 < d; i0 += kDimChunk) {
    const int i1 = std::min(d, i0 + kDimChunk);
    const bool first = i0 == 0;
    for (int b = 0; b < n; ++b) {
      double* col = R + static_cast<std::size_t>(b) * ld;
      int a = b + 1;
      for (; a + kTile <= n; a += kTile) distance_tile<V>(Xt, ld, i0, i1, b, a, first, col + a);
      for (; a + L <= n; a += L) {  // one register
        V s = first ? V{} : load<V>(col + a);
        for (int i = i0; i < i1; ++i) {
          const V t = load<V>(Xt + static_cast<std::size_t>(i) * ld + a) - Xt[static_cast<std::size_t>(i) * ld + b];
          s += t * t;
        }
        store(col + a, s);
      }
      for (; a < n; ++a) {  // the last points, one at a time
        double s = first ? 0.0 : col[a];
        for (int i = i0; i < i1; ++i) {
          const double t = Xt[static_cast<std::size_t>(i) * ld + a] - Xt[static_cast<std::size_t>(i) * ld + b];
          s += t * t;
        }
        col[a] = s;
      }
    }
  }
}

// gl[i0, i0 + kTileRegisters L) += the terms of the pairs (a > b) of one b, the sums held in
// registers across the points a (each still adds its pairs in the order a = b + 1, b + 2, ...).
// P (n x kTileRegisters L, row-major): the tile's dimensions of every point, contiguous.
template <class V>
[[gnu::always_inline]] inline void gradient_tile(const double* P, int n, int b, const double* cb, double* gl) {
  constexpr int L = static_cast<int>(sizeof(V) / sizeof(double));
  constexpr int kTile = kTileRegisters * L;
  // b's coordinates are read from memory (the L1 cache) at every a: held in registers too, they
  // made GCC spill the sums of the SSE2 copy to the stack (16 registers)
  const double* xb = P + static_cast<std::size_t>(b) * kTile;
  V g0 = load<V>(gl), g1 = load<V>(gl + L), g2 = load<V>(gl + 2 * L), g3 = load<V>(gl + 3 * L);
  for (int a = b + 1; a < n; ++a) {
    const double* xa = P + static_cast<std::size_t>(a) * kTile;
    const double c = cb[a];
    const V t0 = load<V>(xa) - load<V>(xb), t1 = load<V>(xa + L) - load<V>(xb + L);
    const V t2 = load<V>(xa + 2 * L) - load<V>(xb + 2 * L), t3 = load<V>(xa + 3 * L) - load<V>(xb + 3 * L);
    g0 += (c * t0) * t0;
    g1 += (c * t1) * t1;
    g2 += (c * t2) * t2;
    g3 += (c * t3) * t3;
  }
  store(gl, g0);
  store(gl + L, g1);
  store(gl + 2 * L, g2);
  store(gl + 3 * L, g3);
}

template <class V>
void ard_gradient_lanes(const double* Xs, int n, int d, const double* C, double* gl) {
  constexpr int L = static_cast<int>(sizeof(V) / sizeof(double));
  constexpr int kTile = kTileRegisters * L;
  const std::size_t ld = static_cast<std::size_t>(n), dd = static_cast<std::size_t>(d);
  // tiles of dimensions in registers, one b after another; each tile's coordinates are first
  // copied point after point (n x kTile, contiguous), so that the sweeps over the points a read
  // memory in order
  thread_local std::vector<double> packed;
  packed.resize(ld * kTile);
  int i0 = 0;
  for (; i0 + kTile <= d; i0 += kTile) {
    for (std::size_t a = 0; a < ld; ++a) std::memcpy(&packed[a * kTile], Xs + a * dd + i0, kTile * sizeof(double));
    for (int b = 0; b < n; ++b) gradient_tile<V>(packed.data(), n, b, C + static_cast<std::size_t>(b) * ld, gl + i0);
  }
  if (i0 == d) return;
  // the last dimensions, pair by pair
  for (int b = 0; b < n; ++b) {
    const double* xb = Xs + static_cast<std::size_t>(b) * dd;
    const double* cb = C + static_cast<std::size_t>(b) * ld;
    for (int a = b + 1; a < n; ++a) {
      const double* xa = Xs + static_cast<std::size_t>(a) * dd;
      const double c = cb[a];
      int i = i0;
      for (; i + L <= d; i += L) {
        const V t = load<V>(xa + i) - load<V>(xb + i);
        store(gl + i, load<V>(gl + i) + (c * t) * t);
      }
      for (; i < d; ++i) {
        const double t = xa[i] - xb[i];
        gl[i] += (c * t) * t;
      }
    }
  }
}

// the kernels over V (GCC's vector of 2 or 4 doubles)
template <class V>
constexpr LaneKernels lane_kernels{&squared_distances_lanes<V>, &ard_gradient_lanes<V>};

}  // namespace
}  // namespace dsb::gp_pairs
