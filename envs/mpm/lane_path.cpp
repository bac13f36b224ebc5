#include "envs/mpm/lane_path.hpp"

#include "envs/mpm/lane_chunks.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace dsb::mpm {

namespace {

// __builtin_cpu_supports("avx2") is true only when the OS saves the YMM state too (libgcc checks
// OSXSAVE and XCR0 before it reports any AVX feature), so the AVX2 code never faults.
bool cpu_has_avx2() {
  static const bool avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2;
}

LanePath read_environment() {
  const char* value = std::getenv("DSB_MPM_LANES");
  if (!value || !*value) return best_lane_path();
  const auto path = parse_lane_path(value);
  if (!path)
    throw std::runtime_error(std::string("DSB_MPM_LANES must be scalar, sse2 or avx2, got '") + value + "'");
  if (!lane_path_available(*path))
    throw std::runtime_error(std::string("DSB_MPM_LANES=") + value + ": this CPU has no AVX2");
  return *path;
}

}  // namespace

const char* lane_path_name(LanePath path) {
  switch (path) {
    case LanePath::scalar: return "scalar";
    case LanePath::sse2: return "sse2";
    case LanePath::avx2: return "avx2";
  }
  return "?";
}

std::optional<LanePath> parse_lane_path(std::string_view name) {
  for (LanePath p : {LanePath::scalar, LanePath::sse2, LanePath::avx2})
    if (name == lane_path_name(p)) return p;
  return std::nullopt;
}

bool lane_path_available(LanePath path) { return path != LanePath::avx2 || cpu_has_avx2(); }

LanePath best_lane_path() { return cpu_has_avx2() ? LanePath::avx2 : LanePath::sse2; }

const LaneKernels* lane_kernels(LanePath path) {
  switch (path) {
    case LanePath::scalar: return nullptr;
    case LanePath::sse2: return &sse2_lane_kernels();
    case LanePath::avx2: return cpu_has_avx2() ? &avx2_lane_kernels() : nullptr;
  }
  return nullptr;
}

LanePath default_lane_path() {
  static const LanePath path = read_environment();
  return path;
}

}  // namespace dsb::mpm
