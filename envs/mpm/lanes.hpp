#pragma once
// Lane types of the MPM engine's lanes path (lane_path.hpp): Pack<R> holds one double per
// particle in each lane of two SIMD registers R, so a Pack<F2> carries 4 particles in SSE2
// registers and a Pack<F4> 8 particles in AVX2 registers. Two registers rather than one give every
// operation two independent chains, which hides the latency of the divisions and square roots
// (one register: about 1.3x slower SVDs, measured); named members rather than an array, which
// GCC kept in memory.
//
// Every operation is one packed IEEE 754 instruction per register (+ - * / sqrt, sign
// operations, compares and blends): each lane rounds exactly as the scalar instruction on the
// same operands, so a computation written with these types gives, lane by lane, the bits of the
// same computation written with double. GCC's generic vector operators are used where they map
// to one instruction; -ffp-contract=off keeps them from fusing into FMA.
//
// This header is compiled once per instruction set: lanes_sse2.cpp includes it as it is, and
// lanes_avx2.cpp includes it inside `#pragma GCC target("avx2")` with DSB_LANES_AVX2 defined,
// which adds the F4 parts (GCC does not define __AVX2__ under the pragma in C++). Everything is
// in an anonymous namespace, so the two copies never meet at link time (an AVX2 copy of a shared
// inline function could otherwise be picked for the SSE2 path).
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(DSB_LANES_AVX2)
#include <immintrin.h>
#endif

namespace dsb::mpm {
namespace {

#define DSB_LANE_INLINE [[gnu::always_inline]] inline

typedef double F2 __attribute__((vector_size(16)));

DSB_LANE_INLINE F2 splat_register(F2*, double d) { return F2{d, d}; }
DSB_LANE_INLINE F2 sqrt_register(F2 a) { return _mm_sqrt_pd(a); }
DSB_LANE_INLINE F2 abs_register(F2 a) { return _mm_andnot_pd(F2{-0.0, -0.0}, a); }
DSB_LANE_INLINE int mask_bits(F2 a, F2 b, bool greater) {
  return _mm_movemask_pd(greater ? _mm_cmpgt_pd(a, b) : _mm_cmplt_pd(a, b));
}

#if defined(DSB_LANES_AVX2)
typedef double F4 __attribute__((vector_size(32)));

DSB_LANE_INLINE F4 splat_register(F4*, double d) { return F4{d, d, d, d}; }
DSB_LANE_INLINE F4 sqrt_register(F4 a) { return _mm256_sqrt_pd(a); }
DSB_LANE_INLINE F4 abs_register(F4 a) { return _mm256_andnot_pd(F4{-0.0, -0.0, -0.0, -0.0}, a); }
DSB_LANE_INLINE int mask_bits(F4 a, F4 b, bool greater) {
  return _mm256_movemask_pd(greater ? _mm256_cmp_pd(a, b, _CMP_GT_OQ) : _mm256_cmp_pd(a, b, _CMP_LT_OQ));
}
#endif

// Copies go register by register: with the implicit (aggregate) copy, GCC stored a Pack<F4> into
// memory through a stack temporary and 16-byte pieces in general registers (a third of the SVD's
// instructions).
template <class R>
struct Pack {
  static constexpr int kPerRegister = static_cast<int>(sizeof(R) / sizeof(double));
  static constexpr int kLanes = 2 * kPerRegister;
  R a, b;
  Pack() = default;
  Pack(R x, R y) : a(x), b(y) {}
  explicit Pack(double d) : a(splat_register(static_cast<R*>(nullptr), d)), b(a) {}
  Pack(const Pack& o) : a(o.a), b(o.b) {}
  Pack& operator=(const Pack& o) {
    a = o.a;
    b = o.b;
    return *this;
  }
};

#define DSB_PACK_BINARY(op)                                                 \
  template <class R>                                                        \
  DSB_LANE_INLINE Pack<R> operator op(const Pack<R>& x, const Pack<R>& y) { \
    return {x.a op y.a, x.b op y.b};                                        \
  }
DSB_PACK_BINARY(+)
DSB_PACK_BINARY(-)
DSB_PACK_BINARY(*)
DSB_PACK_BINARY(/)
#undef DSB_PACK_BINARY

template <class R>
DSB_LANE_INLINE Pack<R> operator-(const Pack<R>& x) {
  return {-x.a, -x.b};
}
template <class R>
DSB_LANE_INLINE Pack<R> sqrt_(const Pack<R>& x) {
  return {sqrt_register(x.a), sqrt_register(x.b)};
}
template <class R>
DSB_LANE_INLINE Pack<R> abs_(const Pack<R>& x) {
  return {abs_register(x.a), abs_register(x.b)};
}

// x < y ? a : b, x == y ? a : b, x > y ? a : b, lane by lane (a false comparison, NaN included,
// takes b, as the scalar ternary does)
template <class R>
DSB_LANE_INLINE Pack<R> sel_lt(const Pack<R>& x, const Pack<R>& y, const Pack<R>& a, const Pack<R>& b) {
  return {x.a < y.a ? a.a : b.a, x.b < y.b ? a.b : b.b};
}
template <class R>
DSB_LANE_INLINE Pack<R> sel_eq(const Pack<R>& x, const Pack<R>& y, const Pack<R>& a, const Pack<R>& b) {
  return {x.a == y.a ? a.a : b.a, x.b == y.b ? a.b : b.b};
}
template <class R>
DSB_LANE_INLINE Pack<R> sel_gt(const Pack<R>& x, const Pack<R>& y, const Pack<R>& a, const Pack<R>& b) {
  return {x.a > y.a ? a.a : b.a, x.b > y.b ? a.b : b.b};
}
template <class R>
DSB_LANE_INLINE Pack<R> sel_ge(const Pack<R>& x, const Pack<R>& y, const Pack<R>& a, const Pack<R>& b) {
  return {x.a >= y.a ? a.a : b.a, x.b >= y.b ? a.b : b.b};
}
template <class R>
DSB_LANE_INLINE Pack<R> sel_le(const Pack<R>& x, const Pack<R>& y, const Pack<R>& a, const Pack<R>& b) {
  return {x.a <= y.a ? a.a : b.a, x.b <= y.b ? a.b : b.b};
}

// true when x > y in some lane
template <class R>
DSB_LANE_INLINE bool any_gt(const Pack<R>& x, const Pack<R>& y) {
  return (mask_bits(x.a, y.a, true) | mask_bits(x.b, y.b, true)) != 0;
}

// lanes from / to kLanes consecutive doubles (unaligned)
template <class R>
DSB_LANE_INLINE R load_register(const double* p) {
  R r;
  std::memcpy(&r, p, sizeof r);
  return r;
}
template <class T>
DSB_LANE_INLINE T load(const double* p) {
  using R = decltype(T::a);
  return T(load_register<R>(p), load_register<R>(p + T::kPerRegister));
}
template <class R>
DSB_LANE_INLINE void store(double* p, const Pack<R>& t) {
  std::memcpy(p, &t.a, sizeof(R));
  std::memcpy(p + Pack<R>::kPerRegister, &t.b, sizeof(R));
}

}  // namespace
}  // namespace dsb::mpm
