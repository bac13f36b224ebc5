#pragma once
// The 3x3 SVD of the MLS-MPM engine and its adjoints (double precision, deterministic).
//
// svd3 / svd3_batch: A = U diag(sigma) V^T with U, V rotations (det +1), sigma(0) >= sigma(1) >=
//   |sigma(2)| and sigma(2) < 0 exactly when det A < 0 (the "invertible FE" convention of Irving,
//   Teran, Fedkiw 2004). Structure of McAdams et al. 2011 ("Computing the singular value
//   decomposition of 3x3 matrices with minimal branching and elementary floating point
//   operations"): cyclic Jacobi on A^T A accumulating V, B = A V, sort B's columns by norm, Givens
//   QR of B. Departures: double precision, exact Jacobi and Givens rotations (sqrt and division,
//   no quaternion or rsqrt approximations), a one-sided Jacobi sweep on B that makes the columns of
//   B orthogonal to round-off relative to their own norms (what A^T A alone cannot give when the
//   singular values are graded), sweep counts chosen to converge to round-off (4 on A^T A, 1
//   one-sided: svd3.cpp says how they were measured), rotations skipped only for off-diagonal
//   entries below 1e-30 of the matrix's scale, and sigma(1), |sigma(2)| clamped to the entry before
//   them where round-off left them an ulp above it. Only + - * / sqrt and selects: the same bits on
//   every x86-64 CPU (with -ffp-contract=off). Valid for |A| between about 1e-70 and 1e70.
//   Accuracy (tests/test_mpm_svd.cpp): ||A - U Sigma V^T|| < 10 eps ||A||, ||V^T V - I|| < 16 eps.
//   Cost on one core (portable -O3 build, 2.6 GHz Xeon): ~100 ns per SVD through svd3_batch,
//   ~375 ns through svd3 (one element cannot hide the latency of its sqrt/division chain).
// svd3_adjoint: the general reverse-mode SVD formula (Townsend 2016, "Differentiating the singular
//   value decomposition"; PyTorch's svd_backward; PlasticineLab's clamped variant).
// iso_uv_adjoint / iso_uu_adjoint: reverse mode of the isotropic maps F -> U diag(f(sigma)) V^T
//   and F -> U diag(g(sigma)) U^T written with divided differences, finite at equal singular values.
#include <array>
#include <cstddef>

#include "envs/mpm/mpm_types.hpp"

namespace dsb::mpm {

struct Svd3 {
  Mat3 U;
  Vec3 sigma;
  Mat3 V;
};

// The SVD of A (see above). Rank-deficient A (a zero column, A = 0, rank 1) give finite results.
Svd3 svd3(const Mat3& A);

// out[i] = svd3(A[i]) for i < n, bit for bit; processes elements in structure-of-arrays chunks so
// that the compiler vectorizes across elements.
void svd3_batch(const Mat3* A, Svd3* out, std::size_t n);

// A compact record of an SVD for a reverse pass: V as a unit quaternion (w, x, y, z) and sigma.
// restore_svd rebuilds U = A V diag(1 / sigma) from A; where a singular value is tiny
// (|sigma_i| < 1e-6 sigma_0, so that U would be inaccurate) it computes svd3(A) again. The restored
// factors equal the original ones to a few ulps, not bit for bit.
using SvdRecord = std::array<double, 7>;
SvdRecord record_svd(const Svd3& s);
Svd3 restore_svd(const SvdRecord& r, const Mat3& A);

// dL/dA from dL/dU, dL/dsigma, dL/dV for A = U diag(sigma) V^T (Townsend 2016 / PyTorch):
//   A_bar = U [diag(sigma_bar) + (K o (U^T U_bar - U_bar^T U)) Sigma
//              + Sigma (K o (V^T V_bar - V_bar^T V))] V^T,
//   K_ij = 1 / (sigma_j^2 - sigma_i^2) (i != j), K_ii = 0, the denominator clamped to
//   |.| >= clamp keeping its sign (a zero denominator counts as positive). Exact for well-separated
//   singular values; biased (not NaN) when two are closer than the clamp allows.
Mat3 svd3_adjoint(const Svd3& s, const Mat3& U_bar, const Vec3& sigma_bar, const Mat3& V_bar, double clamp = 1e-6);

// Denominators sigma_i + sigma_j of the isotropic adjoints are kept at |.| >= this (sign kept; a
// zero counts as positive). They vanish only under inversion (sigma_i = -sigma_j, e.g. a matrix of
// rank <= 1), where the maps are not differentiable in general; the guard keeps the result finite.
inline constexpr double kIsoDenominatorFloor = 1e-100;

// Adjoint of X = U diag(f) V^T, f = f(sigma), with respect to F = U diag(sigma) V^T (s = svd3(F)).
//   dfds(i, j) = d f_i / d sigma_j; dd(i, j) = (f_i - f_j) / (sigma_i - sigma_j) for i != j (the
//   caller's stable divided difference, its limit f' at equal singular values; the diagonal is not
//   read). With G = U^T X_bar V: F_bar = U H V^T,
//   H_ii = sum_j dfds(j, i) G_jj,
//   H_ij = (a + b)/2 G_ij + (a - b)/2 G_ji (i != j), a = dd(i, j), b = (f_i + f_j)/(sigma_i + sigma_j).
Mat3 iso_uv_adjoint(const Svd3& s, const Vec3& f, const Mat3& dfds, const Mat3& dd, const Mat3& X_bar);

// Adjoint of the symmetric T = U diag(g) U^T, g = g(sigma), with respect to F (s = svd3(F)).
//   dgds(i, j) = d g_i / d sigma_j; ddg(i, j) = (g_i - g_j) / (sigma_i - sigma_j) (stable, its
//   limit at equal singular values). With S = sym(U^T T_bar U): F_bar = U H V^T,
//   H_ii = sum_j dgds(j, i) S_jj; for i < j, e_ij = ddg(i, j) / (sigma_i + sigma_j):
//   H_ij = 2 S_ij e_ij sigma_j, H_ji = 2 S_ij e_ij sigma_i.
Mat3 iso_uu_adjoint(const Svd3& s, const Mat3& dgds, const Mat3& ddg, const Mat3& T_bar);

}  // namespace dsb::mpm
