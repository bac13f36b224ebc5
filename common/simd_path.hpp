#pragma once
// The one CPU dispatch of every batched kernel: the batched exp/log of common/det_math.hpp, the
// GP's pairwise loops (optimizers/bo/gp_pairs.hpp) and the MPM engine's per-particle lanes
// (envs/mpm/lane_path.hpp). A kernel family offers some of the paths below; each path gives
// exactly the bits of the family's scalar code (see the kernels' headers for why), so the choice
// changes speed only, never a result. The build stays portable (no -march): the AVX and AVX2 code
// lives in functions compiled with __attribute__((target(...))), and the choice is made at run
// time.
//
// The paths run from narrow to wide, each wider one needing the features of those before it. The
// widest this process may take, its ceiling, is the widest the CPU has, or the one the environment
// variable DSB_SIMD=scalar|sse2|avx|avx2 names (read once per process; tests/check_cpu_features.sh
// runs a grid with DSB_SIMD=sse2, as a CPU without AVX would run it). Each family takes the widest
// path it offers at or below the ceiling.
#include <cstdlib>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace dsb {

enum class SimdPath { scalar, sse2, avx, avx2 };

inline const char* simd_path_name(SimdPath path) {
  switch (path) {
    case SimdPath::scalar: return "scalar";
    case SimdPath::sse2: return "sse2";
    case SimdPath::avx: return "avx";
    case SimdPath::avx2: return "avx2";
  }
  return "?";
}

inline std::optional<SimdPath> parse_simd_path(std::string_view name) {
  for (SimdPath p : {SimdPath::scalar, SimdPath::sse2, SimdPath::avx, SimdPath::avx2})
    if (name == simd_path_name(p)) return p;
  return std::nullopt;
}

// scalar and sse2 (part of x86-64): every CPU; avx, avx2 where the CPU and the OS support them
// (__builtin_cpu_supports reports an AVX feature only when the OS saves the YMM state too: libgcc
// checks OSXSAVE and XCR0, so that code never faults)
inline bool cpu_supports(SimdPath path) {
  static const bool avx = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx") != 0;
  }();
  static const bool avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return path == SimdPath::avx2 ? avx2 : path == SimdPath::avx ? avx : true;
}

// The widest path this process may take: DSB_SIMD when set, else the widest the CPU supports.
// Throws std::runtime_error naming the variable for an unknown path or one this CPU lacks, and
// for DSB_MPM_LANES, which DSB_SIMD replaced (5d65cfe): a leftover setting would otherwise be
// ignored without a word, and a timing taken under it would not be of the path it names.
inline SimdPath simd_ceiling() {
  static const SimdPath ceiling = [] {
    if (const char* old = std::getenv("DSB_MPM_LANES"))
      throw std::runtime_error(std::string("DSB_MPM_LANES is no longer read (got '") + old +
                               "'): set DSB_SIMD=scalar|sse2|avx|avx2 instead, and unset DSB_MPM_LANES");
    const char* value = std::getenv("DSB_SIMD");
    if (!value || !*value)
      return cpu_supports(SimdPath::avx2) ? SimdPath::avx2
          : cpu_supports(SimdPath::avx)   ? SimdPath::avx
                                          : SimdPath::sse2;
    const auto path = parse_simd_path(value);
    if (!path) throw std::runtime_error(std::string("DSB_SIMD must be scalar, sse2, avx or avx2, got '") + value + "'");
    if (!cpu_supports(*path)) throw std::runtime_error(std::string("DSB_SIMD=") + value + ": this CPU has no " + value);
    return *path;
  }();
  return ceiling;
}

// the widest of a family's paths (`offered`, narrow to wide) at or below the ceiling; the
// narrowest it offers when none is (a family without a scalar path under DSB_SIMD=scalar)
inline SimdPath simd_path(std::initializer_list<SimdPath> offered) {
  SimdPath chosen = *offered.begin();
  for (SimdPath p : offered)
    if (p <= simd_ceiling()) chosen = p;
  return chosen;
}

}  // namespace dsb
