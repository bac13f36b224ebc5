// The 3x3 SVD and its adjoints (declarations and conventions: svd3.hpp).
//
// One kernel template serves both svd3 (T = double) and svd3_batch (T = Lanes<W>, W elements in
// structure-of-arrays form whose lane-wise loops GCC vectorizes): the same operations in the same
// order, so the batch gives the same bits as the scalar call. Data-dependent choices are selects
// (lane-wise ternaries, compiled to and/andnot/or blends), never branches or iteration counts.
#include "envs/mpm/svd3.hpp"

#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dsb::mpm {
namespace {

// ---- lane types: double, and W doubles (W/2 SSE2 registers) processed lane by lane ------------
// GCC's generic vector extension: every operator is one packed instruction per register pair of
// lanes, and a ternary on a vector comparison is a blend (the auto-vectorizer, given plain lane
// loops, turned some selects into branches). sqrt is correctly rounded in IEEE 754, so sqrtpd and
// sqrtsd agree bit for bit, as do the packed and scalar + - * /.

#define DSB_INLINE [[gnu::always_inline]] inline
#define DSB_UNROLL _Pragma("GCC unroll 8")

typedef double F2 __attribute__((vector_size(16)));

template <int W>
struct Lanes {
  static_assert(W % 2 == 0 && W > 0, "whole registers of two lanes");
  static constexpr int kRegs = W / 2;
  F2 x[kRegs];
  Lanes() = default;
  explicit Lanes(double d) {
    for (int k = 0; k < kRegs; ++k) x[k] = F2{d, d};
  }
};

#define DSB_LANE_BINOP(op)                                                      \
  template <int W>                                                              \
  DSB_INLINE Lanes<W> operator op(const Lanes<W>& a, const Lanes<W>& b) {       \
    Lanes<W> r;                                                                 \
    DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = a.x[k] op b.x[k];        \
    return r;                                                                   \
  }
DSB_LANE_BINOP(+)
DSB_LANE_BINOP(-)
DSB_LANE_BINOP(*)
DSB_LANE_BINOP(/)
#undef DSB_LANE_BINOP

template <int W>
DSB_INLINE Lanes<W> operator-(const Lanes<W>& a) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = -a.x[k];
  return r;
}

DSB_INLINE F2 sqrt2(F2 a) {
#if defined(__SSE2__)
  return _mm_sqrt_pd(a);
#else
  return F2{std::sqrt(a[0]), std::sqrt(a[1])};
#endif
}
DSB_INLINE F2 abs2(F2 a) {
#if defined(__SSE2__)
  return _mm_andnot_pd(F2{-0.0, -0.0}, a);
#else
  return F2{std::fabs(a[0]), std::fabs(a[1])};
#endif
}

template <int W>
DSB_INLINE Lanes<W> sqrt_(const Lanes<W>& a) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = sqrt2(a.x[k]);
  return r;
}
DSB_INLINE double sqrt_(double a) { return std::sqrt(a); }

template <int W>
DSB_INLINE Lanes<W> abs_(const Lanes<W>& a) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = abs2(a.x[k]);
  return r;
}
DSB_INLINE double abs_(double a) { return std::fabs(a); }

// x < y ? a : b, and x == y ? a : b, lane by lane
template <int W>
DSB_INLINE Lanes<W> sel_lt(const Lanes<W>& x, const Lanes<W>& y, const Lanes<W>& a,
                           const Lanes<W>& b) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = x.x[k] < y.x[k] ? a.x[k] : b.x[k];
  return r;
}
DSB_INLINE double sel_lt(double x, double y, double a, double b) { return x < y ? a : b; }
template <int W>
DSB_INLINE Lanes<W> sel_eq(const Lanes<W>& x, const Lanes<W>& y, const Lanes<W>& a,
                           const Lanes<W>& b) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = x.x[k] == y.x[k] ? a.x[k] : b.x[k];
  return r;
}
DSB_INLINE double sel_eq(double x, double y, double a, double b) { return x == y ? a : b; }

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
DSB_INLINE Rot<T> jacobi_rotation(const T& app, const T& aqq, const T& apq, const T& thr) {
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
DSB_INLINE void rotate_columns(T (&x)[3], T (&y)[3], const T& c, const T& s) {
  for (int k = 0; k < 3; ++k) {
    const T xk = c * x[k] - s * y[k];
    const T yk = s * x[k] + c * y[k];
    x[k] = xk;
    y[k] = yk;
  }
}

template <class T>
DSB_INLINE T dot3(const T (&x)[3], const T (&y)[3]) {
  return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
}

// one Jacobi step on S = A^T A for the pair (p, q), r the third index: S <- J^T S J, V <- V J
template <class T>
DSB_INLINE void sym_step(T& spp, T& sqq, T& spq, T& srp, T& srq, T (&vp)[3], T (&vq)[3],
                         const T& thr) {
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
DSB_INLINE void col_step(T (&bp)[3], T (&bq)[3], T (&vp)[3], T (&vq)[3]) {
  const T alpha = dot3(bp, bp), beta = dot3(bq, bq);
  const Rot<T> g = jacobi_rotation(alpha, beta, dot3(bp, bq), T(kTau) * (alpha + beta) + T(kFloor));
  rotate_columns(bp, bq, g.c, g.s);
  rotate_columns(vp, vq, g.c, g.s);
}

// columns i, j of B and V swapped (one negated, so det V stays +1) where |b_i| < |b_j|
template <class T>
DSB_INLINE void sort_step(T& ni, T& nj, T (&bi)[3], T (&bj)[3], T (&vi)[3], T (&vj)[3]) {
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
DSB_INLINE Rot<T> givens(const T& x, const T& y) {
  const T zero(0.0), one(1.0);
  const T rho = sqrt_(x * x + y * y);
  const T inv = one / sel_eq(rho, zero, one, rho);
  return {sel_eq(rho, zero, one, x * inv), y * inv, rho};  // t holds rho
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
  const Rot<T> g1 = givens(b[0][0], b[0][1]);
  for (int j = 1; j < 3; ++j) {
    const T x = g1.c * b[j][0] + g1.s * b[j][1];
    const T y = g1.c * b[j][1] - g1.s * b[j][0];
    b[j][0] = x;
    b[j][1] = y;
  }
  b[0][0] = g1.t;
  const Rot<T> g2 = givens(b[0][0], b[0][2]);
  for (int j = 1; j < 3; ++j) {
    const T x = g2.c * b[j][0] + g2.s * b[j][2];
    const T y = g2.c * b[j][2] - g2.s * b[j][0];
    b[j][0] = x;
    b[j][2] = y;
  }
  b[0][0] = g2.t;
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

template <int W>
void batch_chunk(const Mat3* A, Svd3* out, std::size_t count) {
  Lanes<W> a[3][3], u[3][3], sigma[3], v[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int l = 0; l < W; ++l)
        a[r][c].x[l / 2][l % 2] = static_cast<std::size_t>(l) < count ? A[l](r, c) : 0.0;
  svd3_kernel(a, u, sigma, v);
  for (std::size_t l = 0; l < count; ++l) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        out[l].U(r, c) = u[c][r].x[l / 2][l % 2];
        out[l].V(r, c) = v[c][r].x[l / 2][l % 2];
      }
    for (int k = 0; k < 3; ++k) out[l].sigma(k) = sigma[k].x[l / 2][l % 2];
  }
}

// 8 lanes (4 SSE2 registers per quantity): enough independent work to hide the latency of the
// sqrt and division chain of each rotation (measured: 2 lanes ~300 ns, 4 ~127 ns, 8 ~100 ns per SVD)
constexpr int kBatchWidth = 8;

}  // namespace

Svd3 svd3(const Mat3& A) {
  double a[3][3], u[3][3], sigma[3], v[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a[r][c] = A(r, c);
  svd3_kernel(a, u, sigma, v);
  Svd3 s;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      s.U(r, c) = u[c][r];
      s.V(r, c) = v[c][r];
    }
  s.sigma = Vec3(sigma[0], sigma[1], sigma[2]);
  return s;
}

void svd3_batch(const Mat3* A, Svd3* out, std::size_t n) {
  std::size_t i = 0;
  for (; i + kBatchWidth <= n; i += kBatchWidth) batch_chunk<kBatchWidth>(A + i, out + i, kBatchWidth);
  if (i < n) batch_chunk<kBatchWidth>(A + i, out + i, n - i);
}

// ---- adjoints -----------------------------------------------------------------------------------

namespace {

// x with |x| raised to at least floor, its sign kept (0 counts as positive)
double away_from_zero(double x, double floor) {
  if (std::fabs(x) >= floor) return x;
  return x < 0.0 ? -floor : floor;
}

}  // namespace

Mat3 svd3_adjoint(const Svd3& s, const Mat3& U_bar, const Vec3& sigma_bar, const Mat3& V_bar,
                  double clamp) {
  Mat3 K = Mat3::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j)
        K(i, j) = 1.0 / away_from_zero(s.sigma(j) * s.sigma(j) - s.sigma(i) * s.sigma(i), clamp);
  const Mat3 Ju = s.U.transpose() * U_bar;
  const Mat3 Jv = s.V.transpose() * V_bar;
  Mat3 M = K.cwiseProduct(Ju - Ju.transpose()) * s.sigma.asDiagonal();
  M += s.sigma.asDiagonal() * K.cwiseProduct(Jv - Jv.transpose());
  M.diagonal() += sigma_bar;
  return s.U * M * s.V.transpose();
}

// Derivation (dF = U dP V^T, dU = U Omega_U, dV = V Omega_V, Omega antisymmetric): off the
// diagonal dP_ij = Omega_U,ij sigma_j - sigma_i Omega_V,ij, so
//   Omega_U,ij = (dP_ij sigma_j + dP_ji sigma_i) / (sigma_j^2 - sigma_i^2),
//   Omega_V,ij = (dP_ij sigma_i + dP_ji sigma_j) / (sigma_j^2 - sigma_i^2);
// dX^ = U^T dX V has dX^_ij = Omega_U,ij f_j - f_i Omega_V,ij
//   = [dP_ij (sigma_j f_j - sigma_i f_i) + dP_ji (sigma_i f_j - sigma_j f_i)] / (sigma_j^2 - sigma_i^2)
//   = (a + b)/2 dP_ij + (a - b)/2 dP_ji, with a, b as in svd3.hpp (expand (a +- b)/2 over the common
// denominator sigma_i^2 - sigma_j^2), and dX^_ii = sum_j dfds(i, j) dP_jj. The adjoint is the
// transpose of that map: the coefficients are symmetric in (i, j), so H_ij collects G_ij through
// (a + b)/2 and G_ji through (a - b)/2.
Mat3 iso_uv_adjoint(const Svd3& s, const Vec3& f, const Mat3& dfds, const Mat3& dd,
                    const Mat3& X_bar) {
  const Mat3 G = s.U.transpose() * X_bar * s.V;
  Mat3 H;
  for (int i = 0; i < 3; ++i) {
    H(i, i) = dfds(0, i) * G(0, 0) + dfds(1, i) * G(1, 1) + dfds(2, i) * G(2, 2);
    for (int j = 0; j < 3; ++j) {
      if (j == i) continue;
      const double a = dd(i, j);
      const double b = (f(i) + f(j)) / away_from_zero(s.sigma(i) + s.sigma(j), kIsoDenominatorFloor);
      H(i, j) = 0.5 * (a + b) * G(i, j) + 0.5 * (a - b) * G(j, i);
    }
  }
  return s.U * H * s.V.transpose();
}

// Derivation: dT^ = U^T dT U has dT^_ij = Omega_U,ij (g_j - g_i) off the diagonal
//   = e_ij (dP_ij sigma_j + dP_ji sigma_i), e_ij = (g_i - g_j) / (sigma_i^2 - sigma_j^2)
//   = ddg(i, j) / (sigma_i + sigma_j),
// and dT^_ii = sum_j dgds(i, j) dP_jj. dT^ is symmetric, so <T_bar, dT> = <S, dT^> with
// S = sym(U^T T_bar U), and each unordered pair {i, j} contributes 2 S_ij e_ij (dP_ij sigma_j +
// dP_ji sigma_i): the formula in svd3.hpp, as given.
Mat3 iso_uu_adjoint(const Svd3& s, const Mat3& dgds, const Mat3& ddg, const Mat3& T_bar) {
  const Mat3 M = s.U.transpose() * T_bar * s.U;
  const Mat3 S = 0.5 * (M + M.transpose());
  Mat3 H;
  for (int i = 0; i < 3; ++i)
    H(i, i) = dgds(0, i) * S(0, 0) + dgds(1, i) * S(1, 1) + dgds(2, i) * S(2, 2);
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      const double e =
          ddg(i, j) / away_from_zero(s.sigma(i) + s.sigma(j), kIsoDenominatorFloor);
      const double w = 2.0 * S(i, j) * e;
      H(i, j) = w * s.sigma(j);
      H(j, i) = w * s.sigma(i);
    }
  return s.U * H * s.V.transpose();
}

SvdRecord record_svd(const Svd3& s) {
  const Eigen::Quaterniond q(s.V);
  return {q.w(), q.x(), q.y(), q.z(), s.sigma[0], s.sigma[1], s.sigma[2]};
}

Svd3 restore_svd(const SvdRecord& r, const Mat3& A) {
  Svd3 s;
  s.sigma = Vec3(r[4], r[5], r[6]);
  if (!(std::abs(s.sigma[2]) >= 1e-6 * s.sigma[0] && std::abs(s.sigma[1]) >= 1e-6 * s.sigma[0])) return svd3(A);
  s.V = Eigen::Quaterniond(r[0], r[1], r[2], r[3]).toRotationMatrix();
  // A V = U diag(sigma)
  const Mat3 AV = A * s.V;
  for (int i = 0; i < 3; ++i) s.U.col(i) = AV.col(i) / s.sigma[i];
  return s;
}

}  // namespace dsb::mpm
