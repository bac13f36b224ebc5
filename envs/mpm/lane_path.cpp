#include "envs/mpm/lane_path.hpp"

#include "envs/mpm/lane_chunks.hpp"

namespace dsb::mpm {

const LaneKernels* lane_kernels(SimdPath path) {
  switch (path) {
    case SimdPath::scalar:
    case SimdPath::avx: return nullptr;  // no lanes of these widths: the scalar phases
    case SimdPath::sse2: return &sse2_lane_kernels();
    case SimdPath::avx2: return cpu_supports(SimdPath::avx2) ? &avx2_lane_kernels() : nullptr;
  }
  return nullptr;
}

SimdPath default_lane_path() {
  static const SimdPath path = simd_path({SimdPath::scalar, SimdPath::sse2, SimdPath::avx2});
  return path;
}

}  // namespace dsb::mpm
