// The 3x3 SVD and its adjoints (declarations and conventions: svd3.hpp).
//
// One kernel template (svd3_kernel.hpp) serves both svd3 (T = double) and svd3_batch (T = Lanes<W>,
// W elements in structure-of-arrays form whose lane-wise loops GCC vectorizes): the same
// operations in the same order, so the batch gives the same bits as the scalar call. Data-dependent
// choices are selects (lane-wise ternaries, compiled to and/andnot/or blends), never branches or
// iteration counts.
#include "envs/mpm/svd3.hpp"
#include "envs/mpm/svd3_kernel.hpp"

#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dsb::mpm {
namespace {

// ---- lane type: W doubles (W/2 SSE2 registers) processed lane by lane --------------------------
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

#define DSB_LANE_BINOP(op)                                                          \
  template <int W>                                                                  \
  DSB_INLINE Lanes<W> operator op(const Lanes<W>& a, const Lanes<W>& b) {           \
    Lanes<W> r;                                                                     \
    DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = a.x[k] op b.x[k]; \
    return r;                                                                       \
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

template <int W>
DSB_INLINE Lanes<W> abs_(const Lanes<W>& a) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = abs2(a.x[k]);
  return r;
}

// x < y ? a : b, and x == y ? a : b, lane by lane
template <int W>
DSB_INLINE Lanes<W> sel_lt(const Lanes<W>& x, const Lanes<W>& y, const Lanes<W>& a, const Lanes<W>& b) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = x.x[k] < y.x[k] ? a.x[k] : b.x[k];
  return r;
}
template <int W>
DSB_INLINE Lanes<W> sel_eq(const Lanes<W>& x, const Lanes<W>& y, const Lanes<W>& a, const Lanes<W>& b) {
  Lanes<W> r;
  DSB_UNROLL for (int k = 0; k < Lanes<W>::kRegs; ++k) r.x[k] = x.x[k] == y.x[k] ? a.x[k] : b.x[k];
  return r;
}

template <int W>
void batch_chunk(const Mat3* A, Svd3* out, std::size_t count) {
  Lanes<W> a[3][3], u[3][3], sigma[3], v[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int l = 0; l < W; ++l) a[r][c].x[l / 2][l % 2] = static_cast<std::size_t>(l) < count ? A[l](r, c) : 0.0;
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

Mat3 svd3_adjoint(const Svd3& s, const Mat3& U_bar, const Vec3& sigma_bar, const Mat3& V_bar, double clamp) {
  Mat3 K = Mat3::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j) K(i, j) = 1.0 / away_from_zero(s.sigma(j) * s.sigma(j) - s.sigma(i) * s.sigma(i), clamp);
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
Mat3 iso_uv_adjoint(const Svd3& s, const Vec3& f, const Mat3& dfds, const Mat3& dd, const Mat3& X_bar) {
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
  for (int i = 0; i < 3; ++i) H(i, i) = dgds(0, i) * S(0, 0) + dgds(1, i) * S(1, 1) + dgds(2, i) * S(2, 2);
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      const double e = ddg(i, j) / away_from_zero(s.sigma(i) + s.sigma(j), kIsoDenominatorFloor);
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
