// gp_pairs.hpp's lanes kernels in SSE2 registers (two doubles), part of every x86-64 CPU.
#include "optimizers/bo/gp_pairs_lanes.hpp"

namespace dsb::gp_pairs {

typedef double V2 __attribute__((vector_size(16)));

void squared_distances_sse2(const double* Xt, int n, int d, double* R) { squared_distances_lanes<V2>(Xt, n, d, R); }
void ard_gradient_sse2(const double* Xs, int n, int d, const double* C, double* gl) {
  ard_gradient_lanes<V2>(Xs, n, d, C, gl);
}

}  // namespace dsb::gp_pairs
