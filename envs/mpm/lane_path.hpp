#pragma once
// Which code runs the MPM engine's per-particle phases: the scalar path (one particle at a time,
// Eigen: the engine as it was first written) or the lanes path, several particles side by side in
// SIMD registers, two per SSE2 register (every x86-64 CPU) or four per AVX2 register. Every path
// gives the same bits: the lanes code repeats each particle's operations of the scalar code in
// the same order (lanes_kernels.hpp says how), and no path changes the order in which the
// particles' contributions are added to a grid node. The choice changes speed only.
//
// The default is the best path the CPU has (avx2, else sse2); the environment variable
// DSB_MPM_LANES=scalar|sse2|avx2, read once per process, forces one (tests and benchmarks; an
// unknown value, or avx2 on a CPU without AVX2, is an error). MpmWorkspace::lanes holds the path
// a workspace uses, so a test can run each path in one process.
#include <optional>
#include <string_view>

namespace dsb::mpm {

enum class LanePath { scalar, sse2, avx2 };

const char* lane_path_name(LanePath path);
std::optional<LanePath> parse_lane_path(std::string_view name);

// true for scalar and sse2; for avx2 when the CPU (and the OS) support AVX2
bool lane_path_available(LanePath path);

// avx2 where available, else sse2
LanePath best_lane_path();

// DSB_MPM_LANES if set (read on the first call), else best_lane_path(). Throws
// std::runtime_error naming the variable for an unknown or unavailable value.
LanePath default_lane_path();

}  // namespace dsb::mpm
