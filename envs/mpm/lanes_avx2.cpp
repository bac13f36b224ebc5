// The lanes kernels for AVX2: Pack<F4>, 8 particles in two registers. Compiled for AVX2 through
// `#pragma GCC target("avx2")` around the kernel headers only (the build stays portable; the
// table is used only where the CPU has AVX2: lane_path.cpp). AVX2 does not imply FMA, and
// -ffp-contract=off keeps products and sums apart in any case.
//
// Every header the kernels use besides the lanes headers is included first, outside the pragma:
// an inline function first defined inside it would be compiled for AVX2, and the linker could
// then give the AVX2 copy to the rest of the program.
#include <cmath>
#include <cstring>
#include <immintrin.h>

#include "common/det_math.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/svd3.hpp"

#pragma GCC push_options
#pragma GCC target("avx2")
#if defined(__FMA__)
#error "the AVX2 lanes must be compiled without FMA (they would not give the scalar bits)"
#endif
#define DSB_LANES_AVX2 1
#include "envs/mpm/lanes.hpp"
#include "envs/mpm/eigen_order.hpp"
#include "envs/mpm/svd3_kernel.hpp"
#include "envs/mpm/stress_lanes.hpp"
#include "envs/mpm/transfer_lanes.hpp"
#include "envs/mpm/adjoint_lanes.hpp"
#include "envs/mpm/solid_adjoint_lanes.hpp"
#include "envs/mpm/lane_kernel_table.hpp"

namespace dsb::mpm {

const LaneKernels& avx2_lane_kernels() {
  static const LaneKernels kernels = lane_kernel_table<F4>();
  return kernels;
}

}  // namespace dsb::mpm
#pragma GCC pop_options
