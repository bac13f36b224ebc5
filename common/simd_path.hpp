#pragma once
// The vector instruction set of the batched kernels (dm::exp_batch / dm::log_batch,
// mpm::svd3_batch): SSE2 (part of x86-64, so every CPU has it) or AVX (256-bit registers, where
// the CPU and the OS support it). The build stays portable (no -march): the AVX code lives in
// functions compiled with __attribute__((target("avx"))), and the choice is made once per process
// at run time. Both paths give exactly the bits of the scalar functions (see the kernels' headers
// for why), so the choice changes speed only, never a result.
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

// the path the batched kernels take: AVX where the CPU has it, else SSE2
inline SimdPath simd_path() { return cpu_has_avx() ? SimdPath::avx : SimdPath::sse2; }

}  // namespace dsb
