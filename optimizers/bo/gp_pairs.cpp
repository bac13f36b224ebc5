// gp_pairs.hpp: the scalar reference loops and the choice of path.
#include "optimizers/bo/gp_pairs.hpp"

#include <cstddef>

#include "optimizers/bo/gp_pairs_lanes.hpp"

namespace dsb::gp_pairs {
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

// the path's loops: the scalar reference, or the lanes of sse2 or avx (avx2 runs the avx code)
LaneKernels kernels(SimdPath path) {
  switch (path) {
    case SimdPath::scalar: return {&squared_distances_scalar, &ard_gradient_scalar};
    case SimdPath::sse2: return sse2_kernels();
    case SimdPath::avx:
    case SimdPath::avx2: return avx_kernels();
  }
  return {&squared_distances_scalar, &ard_gradient_scalar};
}

}  // namespace

SimdPath default_path() { return simd_path({SimdPath::scalar, SimdPath::sse2, SimdPath::avx}); }

void squared_distances(const double* Xt, int n, int d, double* R, SimdPath path) {
  kernels(path).squared_distances(Xt, n, d, R);
}

void ard_gradient(const double* Xs, int n, int d, const double* C, double* gl, SimdPath path) {
  kernels(path).ard_gradient(Xs, n, d, C, gl);
}

}  // namespace dsb::gp_pairs
