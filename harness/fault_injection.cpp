#include "harness/fault_injection.hpp"

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace dsb {

std::int64_t fault_kill_after_episodes() {
#ifdef DSB_FAULT_INJECTION
  static const std::int64_t armed = [] {
    const char* mode = std::getenv("DSB_FAULT_INJECTION");
    const char* count = std::getenv("DSB_FAULT_KILL_AFTER_EPISODES");
    if (!mode || std::strcmp(mode, "kill-after-episodes") != 0 || !count) return std::int64_t{-1};
    const long long k = std::atoll(count);
    std::fprintf(stderr, "harness: fault injection armed: SIGKILL after %lld episodes\n", k);
    return static_cast<std::int64_t>(k);
  }();
  return armed;
#else
  return -1;
#endif
}

void fault_maybe_kill(std::int64_t episodes) {
  const std::int64_t at = fault_kill_after_episodes();
  if (at >= 0 && episodes >= at) std::raise(SIGKILL);
}

}  // namespace dsb
