// The lanes kernels for SSE2 (every x86-64 CPU): Pack<F2>, 4 particles in two registers.
#include "envs/mpm/stress_lanes.hpp"
#include "envs/mpm/transfer_lanes.hpp"
#include "envs/mpm/adjoint_lanes.hpp"
#include "envs/mpm/solid_adjoint_lanes.hpp"

namespace dsb::mpm {

const LaneKernels& sse2_lane_kernels() {
  static const LaneKernels kernels{&solid_stress_chunk<Pack<F2>>, &p2g_chunk<Pack<F2>>,
                                   &g2p_chunk<Pack<F2>>,          &g2p_adjoint_chunk<Pack<F2>>,
                                   &p2g_adjoint_gather<F2>,       &solid_adjoint_chunk<Pack<F2>>};
  return kernels;
}

}  // namespace dsb::mpm
