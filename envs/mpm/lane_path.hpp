#pragma once
// Which code runs the MPM engine's per-particle phases: the scalar path (one particle at a time,
// Eigen: the engine as it was first written) or the lanes paths, several particles side by side in
// SIMD registers, two per SSE2 register (every x86-64 CPU) or four per AVX2 register. Every path
// gives the same bits: the lanes code repeats each particle's operations of the scalar code in
// the same order (lanes_kernels.hpp says how), and no path changes the order in which the
// particles' contributions are added to a grid node. The choice changes speed only.
//
// The paths are common/simd_path.hpp's, the one dispatch of every batched kernel: the engine
// offers scalar, sse2 and avx2, and takes the widest at or below the process's ceiling (the best
// the CPU has, or DSB_SIMD). MpmWorkspace::lanes holds the path a workspace uses, so a test can
// run each path in one process.
#include "common/simd_path.hpp"

namespace dsb::mpm {

// the widest of scalar, sse2 and avx2 at or below simd_ceiling(): avx2 where the CPU has it,
// else sse2, unless DSB_SIMD says narrower
SimdPath default_lane_path();

}  // namespace dsb::mpm
