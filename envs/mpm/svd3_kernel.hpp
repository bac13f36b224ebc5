#pragma once
// The kernel of the 3x3 SVD (svd3.hpp), a template on its number type T: double (svd3), the SSE2
// lanes of svd3_batch (svd3.cpp) and the lanes path's Pack types (lanes.hpp). Every T runs the
// same operations in the same order, so each lane of a batch gives the bits of svd3 on its
// matrix. Data-dependent choices are selects (sel_lt, sel_eq: lane-wise ternaries), never
// branches or iteration counts. T needs + - * /, unary -, construction from a double, and
// sqrt_, abs_, sel_lt, sel_eq found by argument-dependent lookup (for double: below).
//
// In an anonymous namespace: each translation unit compiles its own copy for its instruction set
// (lanes_avx2.cpp includes this header inside `#pragma GCC target("avx2")`), and the copies must
// not be merged at link time.
#include <cmath>

namespace dsb::mpm {
namespace {

#define DSB_SVD_INLINE [[gnu::always_inline]] inline

DSB_SVD_INLINE double sqrt_(double a) { return std::sqrt(a); }
DSB_SVD_INLINE double abs_(double a) { return std::fabs(a); }
// x < y ? a : b, and x == y ? a : b
DSB_SVD_INLINE double sel_lt(double x, double y, double a, double b) { return x < y ? a : b; }
DSB_SVD_INLINE double sel_eq(double x, double y, double a, double b) { return x == y ? a : b; }

// ---- the kernel --------------------------------------------------------------------------------

// The Jacobi rotation that zeroes the off-diagonal entry of the symmetric 2x2 [[app, apq],
// [apq, aqq]]: J = [[c, s], [-s, c]] with t = s / c the smaller root of t^2 + 2 theta t - 1 = 0,
// theta = (aqq - app) / (2 apq): the stable t = sign(theta) / (|theta| + sqrt(theta^2 + 1)),
// c = 1 / sqrt(1 + t^2), s = t c. With d = aqq - app, e = 2 apq that t is
// sign(d) e / (|d| + sqrt(d^2 + e^2)) (sign(0) = +1): one division fewer, and no overflow of
// theta^2 when apq is tiny. The rotation is skipped (d = 1, e = 0 give c = 1, s = t = 0 exactly)
// when |e| <= thr, which the callers set to 1e-30 of the scale of the matrix plus 1e-150: an entry
// that small is far below round-off, and the floor keeps d^2 + e^2 a normal double (an exactly
// zero entry is skipped, as Jacobi requires, and so is one that would underflow). The squares
// limit the range to |A| within about 1e-70 .. 1e70 (S ~ A^2, d^2 ~ A^4).
constexpr double kTau = 1e-30, kFloor = 1e-150;
template <class T>
struct Rot {
  T c, s, t;
};
template <class T>
DSB_SVD_INLINE Rot<T> jacobi_rotation(const T& app, const T& aqq, const T& apq, const T& thr) {
  const T zero(0.0), one(1.0);
  const T e0 = apq + apq;
  const T e = sel_lt(thr, abs_(e0), e0, zero);
  const T d = sel_lt(thr, abs_(e0), aqq - app, one);
  const T es = sel_lt(d, zero, -e, e);
  const T t = es / (abs_(d) + sqrt_(d * d + e * e));
  const T c = one / sqrt_(one + t * t);
  return {c, t * c, t};
}

// columns x, y <- c x - s y, s x + c y
template <class T>
DSB_SVD_INLINE void rotate_columns(T (&x)[3], T (&y)[3], const T& c, const T& s) {
  for (int k = 0; k < 3; ++k) {
    const T xk = c * x[k] - s * y[k];
    const T yk = s * x[k] + c * y[k];
    x[k] = xk;
    y[k] = yk;
  }
}

template <class T>
DSB_SVD_INLINE T dot3(const T (&x)[3], const T (&y)[3]) {
  return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
}

// one Jacobi step on S = A^T A for the pair (p, q), r the third index: S <- J^T S J, V <- V J
template <class T>
DSB_SVD_INLINE void sym_step(T& spp, T& sqq, T& spq, T& srp, T& srq, T (&vp)[3], T (&vq)[3], const T& thr) {
  const Rot<T> g = jacobi_rotation(spp, sqq, spq, thr);
  spp = spp - g.t * spq;
  sqq = sqq + g.t * spq;
  spq = T(0.0);
  const T rp = g.c * srp - g.s * srq;
  const T rq = g.s * srp + g.c * srq;
  srp = rp;
  srq = rq;
  rotate_columns(vp, vq, g.c, g.s);
}

// one one-sided (Hestenes) Jacobi step on the columns p, q of B = A V: the rotation computed from
// the current columns, so that their angle is settled relative to their own norms
template <class T>
DSB_SVD_INLINE void col_step(T (&bp)[3], T (&bq)[3], T (&vp)[3], T (&vq)[3]) {
  const T alpha = dot3(bp, bp), beta = dot3(bq, bq);
  const Rot<T> g = jacobi_rotation(alpha, beta, dot3(bp, bq), T(kTau) * (alpha + beta) + T(kFloor));
  rotate_columns(bp, bq, g.c, g.s);
  rotate_columns(vp, vq, g.c, g.s);
}

// columns i, j of B and V swapped (one negated, so det V stays +1) where |b_i| < |b_j|
template <class T>
DSB_SVD_INLINE void sort_step(T& ni, T& nj, T (&bi)[3], T (&bj)[3], T (&vi)[3], T (&vj)[3]) {
  for (int k = 0; k < 3; ++k) {
    const T b_i = sel_lt(ni, nj, bj[k], bi[k]);
    const T b_j = sel_lt(ni, nj, -bi[k], bj[k]);
    const T v_i = sel_lt(ni, nj, vj[k], vi[k]);
    const T v_j = sel_lt(ni, nj, -vi[k], vj[k]);
    bi[k] = b_i;
    bj[k] = b_j;
    vi[k] = v_i;
    vj[k] = v_j;
  }
  const T n_i = sel_lt(ni, nj, nj, ni);
  const T n_j = sel_lt(ni, nj, ni, nj);
  ni = n_i;
  nj = n_j;
}

// Givens rotation [[c, s], [-s, c]] with c x + s y = rho = sqrt(x^2 + y^2) >= 0, -s x + c y = 0;
// the identity when x = y = 0
template <class T>
DSB_SVD_INLINE Rot<T> givens(const T& x, const T& y) {
  const T zero(0.0), one(1.0);
  const T rho = sqrt_(x * x + y * y);
  const T inv = one / sel_eq(rho, zero, one, rho);
  return {sel_eq(rho, zero, one, x * inv), y * inv, rho};  // t holds rho
}

// One Givens step of the QR below on B by columns (b[col][row]): G = givens(B(0,0), B(q,0)) applied
// to rows (0, q), (b_0, b_q) <- (c b_0 + s b_q, c b_q - s b_0), in columns 1 and 2; B(0,0) <- rho
// (B(q,0), now zero, is not read again). Returns G.
template <class T>
DSB_SVD_INLINE Rot<T> givens_clear_column0(T (&b)[3][3], int q) {
  const Rot<T> g = givens(b[0][0], b[0][q]);
  for (int j = 1; j < 3; ++j) {
    const T x = g.c * b[j][0] + g.s * b[j][q];
    const T y = g.c * b[j][q] - g.s * b[j][0];
    b[j][0] = x;
    b[j][q] = y;
  }
  b[0][0] = g.t;
  return g;
}

// Sweep counts: kSymSweeps cyclic sweeps of (0,1), (1,2), (0,2) on S = A^T A, then kColSweeps
// one-sided sweeps on B = A V. Measured with a throwaway probe over 300,000 seeded matrices per
// family (Gaussian, Gaussian x 1e8 and x 1e-8, I + 1e-6 N and I + 1e-12 N, rotations,
// R1 diag(s) R2 with repeated, near-equal (1e-9), graded (1, 1e-8, 1e-9), negative and zero s,
// rank 1, zero columns), the worst off(S) / ||S||_F after sweeps 1, 2, 3, 4 was
//   Gaussian 3.1e-1, 5.0e-2, 1.2e-5, 7.2e-21;  I + 1e-6 N 2.3e-6, 3.7e-7, 4.9e-11, 1.3e-26;
//   R (3,2,-1) R 2.8e-1, 4.1e-2, 1.8e-6, 4.3e-24;  rotations: round-off (< 3e-16) from the start.
// Three sweeps leave 1e-5; the fourth (quadratic convergence) takes that to 7e-21, five orders
// below eps = 2.2e-16, so 4. The one-sided sweep is not for convergence: S itself carries an
// error of eps ||A||^2, which misplaces singular vectors whose singular values are small (without
// it, graded inputs (1, 1e-8, 1e-9) reconstruct with 3e7 eps ||A|| of error, (1, 1e-3, 0) with
// 600 eps); one sweep of rotations computed from B's columns makes them orthogonal relative to
// their own norms. With 4 + 1 the worst over all families: reconstruction 9.6 eps ||A||,
// ||U^T U - I|| 8.2 eps, ||V^T V - I|| 16 eps, singular values 12 eps sigma_max off Eigen's.
// Starting the sweeps from the previous substep's V was measured on real particles and not taken:
// the same accuracy still needs 4 sweeps, and the SVD is about a fifth of a forward episode
// (docs/performance.md, "A warm-started SVD").
constexpr int kSymSweeps = 4;
constexpr int kColSweeps = 1;

// A: a[row][col]; U, V: u[col][row] (columns); sigma.
template <class T>
void svd3_kernel(const T (&a)[3][3], T (&u)[3][3], T (&sigma)[3], T (&v)[3][3]) {
  const T zero(0.0), one(1.0);
  // S = A^T A (upper triangle)
  T s00 = a[0][0] * a[0][0] + a[1][0] * a[1][0] + a[2][0] * a[2][0];
  T s11 = a[0][1] * a[0][1] + a[1][1] * a[1][1] + a[2][1] * a[2][1];
  T s22 = a[0][2] * a[0][2] + a[1][2] * a[1][2] + a[2][2] * a[2][2];
  T s01 = a[0][0] * a[0][1] + a[1][0] * a[1][1] + a[2][0] * a[2][1];
  T s02 = a[0][0] * a[0][2] + a[1][0] * a[1][2] + a[2][0] * a[2][2];
  T s12 = a[0][1] * a[0][2] + a[1][1] * a[1][2] + a[2][1] * a[2][2];
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) v[j][k] = j == k ? one : zero;
  const T thr = T(kTau) * ((s00 + s11) + s22) + T(kFloor);

  for (int sweep = 0; sweep < kSymSweeps; ++sweep) {
    sym_step(s00, s11, s01, s02, s12, v[0], v[1], thr);  // (0,1), r = 2
    sym_step(s11, s22, s12, s01, s02, v[1], v[2], thr);  // (1,2), r = 0
    sym_step(s00, s22, s02, s01, s12, v[0], v[2], thr);  // (0,2), r = 1
  }

  // B = A V (columns)
  T b[3][3];
  for (int j = 0; j < 3; ++j)
    for (int r = 0; r < 3; ++r) b[j][r] = a[r][0] * v[j][0] + a[r][1] * v[j][1] + a[r][2] * v[j][2];

  for (int sweep = 0; sweep < kColSweeps; ++sweep) {
    col_step(b[0], b[1], v[0], v[1]);
    col_step(b[1], b[2], v[1], v[2]);
    col_step(b[0], b[2], v[0], v[2]);
  }

  // columns by decreasing norm (a sorting network of three compare-swaps)
  T n0 = dot3(b[0], b[0]), n1 = dot3(b[1], b[1]), n2 = dot3(b[2], b[2]);
  sort_step(n0, n1, b[0], b[1], v[0], v[1]);
  sort_step(n1, n2, b[1], b[2], v[1], v[2]);
  sort_step(n0, n1, b[0], b[1], v[0], v[1]);

  // Givens QR: B = U R. Rows (0,1) eliminate B(1,0), rows (0,2) B(2,0), rows (1,2) B(2,1).
  // U starts as the identity; U <- U G^T (columns i, j <- c u_i + s u_j, -s u_i + c u_j).
  const Rot<T> g1 = givens_clear_column0(b, 1);
  const Rot<T> g2 = givens_clear_column0(b, 2);
  const Rot<T> g3 = givens(b[1][1], b[1][2]);
  {
    const T y = g3.c * b[2][2] - g3.s * b[2][1];
    b[2][2] = y;
  }
  b[1][1] = g3.t;
  // U = G1^T G2^T G3^T, written out: after G1 u0 = (c1, s1, 0), u1 = (-s1, c1, 0), u2 = e2
  u[0][0] = g2.c * g1.c;
  u[0][1] = g2.c * g1.s;
  u[0][2] = g2.s;
  const T u2_0 = -(g2.s * g1.c), u2_1 = -(g2.s * g1.s), u2_2 = g2.c;
  const T u1_0 = -g1.s, u1_1 = g1.c;
  u[1][0] = g3.c * u1_0 + g3.s * u2_0;
  u[1][1] = g3.c * u1_1 + g3.s * u2_1;
  u[1][2] = g3.s * u2_2;
  u[2][0] = g3.c * u2_0 - g3.s * u1_0;
  u[2][1] = g3.c * u2_1 - g3.s * u1_1;
  u[2][2] = g3.c * u2_2;

  // sigma = diag(R): R00, R11 >= 0 by construction, R22 carries the sign of det A. Round-off can
  // leave R11 a few ulp above R00 (or |R22| above R11) when singular values are (nearly) equal;
  // clamping those is a perturbation of the same size, within the backward error.
  sigma[0] = b[0][0];
  sigma[1] = sel_lt(b[0][0], b[1][1], b[0][0], b[1][1]);
  const T neg = -sigma[1];
  sigma[2] = sel_lt(sigma[1], b[2][2], sigma[1], sel_lt(b[2][2], neg, neg, b[2][2]));
}

}  // namespace
}  // namespace dsb::mpm
