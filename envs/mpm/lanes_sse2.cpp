// The lanes kernels for SSE2 (every x86-64 CPU): Pack<F2>, 4 particles in two registers.
#include "envs/mpm/lane_kernel_table.hpp"

namespace dsb::mpm {

const LaneKernels& sse2_lane_kernels() {
  static const LaneKernels kernels = lane_kernel_table<F2>();
  return kernels;
}

}  // namespace dsb::mpm
