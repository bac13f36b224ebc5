// gp_pairs.hpp's lanes kernels in AVX registers (four doubles), compiled for AVX through
// `#pragma GCC target("avx")` around the kernel header only (the build stays portable;
// gp_pairs.cpp calls them only where the CPU has AVX). AVX does not imply FMA, and
// -ffp-contract=off keeps products and sums apart in any case.
//
// The standard headers the kernels use are included first, outside the pragma: an inline function
// first defined inside it would be compiled for AVX, and the linker could give that copy to the
// rest of the program.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

#pragma GCC push_options
#pragma GCC target("avx")
#if defined(__FMA__)
#error "the AVX kernels must be compiled without FMA (they would not give the scalar bits)"
#endif
#include "optimizers/bo/gp_pairs_lanes.hpp"

namespace dsb::gp_pairs {

typedef double V4 __attribute__((vector_size(32)));

const LaneKernels& avx_kernels() { return lane_kernels<V4>; }

}  // namespace dsb::gp_pairs

#pragma GCC pop_options
