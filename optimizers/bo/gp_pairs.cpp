// gp_pairs.hpp: the scalar reference loops and the choice of path.
#include "optimizers/bo/gp_pairs.hpp"

#include <cstddef>

namespace dsb::gp_pairs {

// gp_pairs_sse2.cpp, gp_pairs_avx.cpp
void squared_distances_sse2(const double* Xt, int n, int d, double* R);
void squared_distances_avx(const double* Xt, int n, int d, double* R);
void ard_gradient_sse2(const double* Xs, int n, int d, const double* C, double* gl);
void ard_gradient_avx(const double* Xs, int n, int d, const double* C, double* gl);

namespace {

void squared_distances_scalar(const double* Xt, int n, int d, double* R) {
  const std::size_t ld = static_cast<std::size_t>(n);
  for (int b = 0; b < n; ++b)
    for (int a = b + 1; a < n; ++a) {
      double s = 0.0;
      for (int i = 0; i < d; ++i) {
        const double t = Xt[i * ld + a] - Xt[i * ld + b];
        s += t * t;
      }
      R[b * ld + a] = s;
    }
}

void ard_gradient_scalar(const double* Xs, int n, int d, const double* C, double* gl) {
  const std::size_t ld = static_cast<std::size_t>(n), dd = static_cast<std::size_t>(d);
  for (int b = 0; b < n; ++b)
    for (int a = b + 1; a < n; ++a) {
      const double c = C[b * ld + a];
      for (int i = 0; i < d; ++i) {
        const double t = Xs[a * dd + i] - Xs[b * dd + i];
        gl[i] += (c * t) * t;
      }
    }
}

}  // namespace

SimdPath default_path() { return simd_path({SimdPath::scalar, SimdPath::sse2, SimdPath::avx}); }

void squared_distances(const double* Xt, int n, int d, double* R, SimdPath path) {
  switch (path) {
    case SimdPath::scalar: return squared_distances_scalar(Xt, n, d, R);
    case SimdPath::sse2: return squared_distances_sse2(Xt, n, d, R);
    case SimdPath::avx:
    case SimdPath::avx2: return squared_distances_avx(Xt, n, d, R);
  }
}

void ard_gradient(const double* Xs, int n, int d, const double* C, double* gl, SimdPath path) {
  switch (path) {
    case SimdPath::scalar: return ard_gradient_scalar(Xs, n, d, C, gl);
    case SimdPath::sse2: return ard_gradient_sse2(Xs, n, d, C, gl);
    case SimdPath::avx:
    case SimdPath::avx2: return ard_gradient_avx(Xs, n, d, C, gl);
  }
}

}  // namespace dsb::gp_pairs
