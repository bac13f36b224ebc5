// gp_pairs.hpp's lanes kernels in SSE2 registers (two doubles), part of every x86-64 CPU.
#include "optimizers/bo/gp_pairs_lanes.hpp"

namespace dsb::gp_pairs {

typedef double V2 __attribute__((vector_size(16)));

const LaneKernels& sse2_kernels() { return lane_kernels<V2>; }

}  // namespace dsb::gp_pairs
