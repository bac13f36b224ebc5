#pragma once
// The vector instruction set of the batched kernels (dm::exp_batch / dm::log_batch,
// mpm::svd3_batch, the GP's pairwise kernels optimizers/bo/gp_pairs.hpp): SSE2 (part of x86-64, so every CPU has it) or AVX (256-bit registers, where
// the CPU and the OS support it). The build stays portable (no -march): the AVX code lives in
// functions compiled with __attribute__((target("avx"))), and the choice is made once per process
// at run time. Both paths give exactly the bits of the scalar functions (see the kernels' headers
// for why), so the choice changes speed only, never a result.
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace dsb {

enum class SimdPath { sse2, avx };

// __builtin_cpu_supports("avx") is true only when the OS saves the YMM state as well (libgcc
// checks OSXSAVE and XCR0), so the AVX path never faults.
inline bool cpu_has_avx() {
  static const bool avx = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx") != 0;
  }();
  return avx;
}

// the path the batched kernels take: AVX where the CPU has it, else SSE2. DSB_SIMD=sse2 in the
// environment takes SSE2 on any CPU (tests/check_cpu_features.sh runs a grid so, as a CPU without
// AVX would run it); DSB_SIMD=avx insists on AVX. Read once per process.
inline SimdPath simd_path() {
  static const SimdPath path = [] {
    const char* value = std::getenv("DSB_SIMD");
    if (!value || !*value) return cpu_has_avx() ? SimdPath::avx : SimdPath::sse2;
    const std::string v = value;
    if (v == "sse2") return SimdPath::sse2;
    if (v != "avx") throw std::runtime_error("DSB_SIMD must be sse2 or avx, got '" + v + "'");
    if (!cpu_has_avx()) throw std::runtime_error("DSB_SIMD=avx: this CPU has no AVX");
    return SimdPath::avx;
  }();
  return path;
}

}  // namespace dsb
