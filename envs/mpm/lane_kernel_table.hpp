#pragma once
// The table of the lanes kernels (lane_chunks.hpp LaneKernels) instantiated for one SIMD register
// type R: F2 in lanes_sse2.cpp, F4 in lanes_avx2.cpp (included there inside its AVX2 pragma, after
// the kernel headers, so the kernels it names are compiled for AVX2). constexpr: the static table
// that holds it is constant-initialized (addresses only), no code of the AVX2 file runs for it.
#include "envs/mpm/adjoint_lanes.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/solid_adjoint_lanes.hpp"
#include "envs/mpm/stress_lanes.hpp"
#include "envs/mpm/transfer_lanes.hpp"

namespace dsb::mpm {

template <class R>
constexpr LaneKernels lane_kernel_table() {
  return LaneKernels{&solid_stress_chunk<Pack<R>>, &p2g_chunk<Pack<R>>,    &g2p_chunk<Pack<R>>,
                     &g2p_adjoint_chunk<Pack<R>>,  &p2g_adjoint_gather<R>, &solid_adjoint_chunk<Pack<R>>};
}

}  // namespace dsb::mpm
