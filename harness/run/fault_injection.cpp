#include "harness/run/fault_injection.hpp"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace dsb {

#ifndef DSB_FAULT_INJECTION
namespace {
// A build without the option ignores the variables; says so once, so that an interruption test run
// against such a build names its cause instead of failing on a run that was never stopped.
void warn_if_requested() {
  static const bool warned = [] {
    const char* mode = std::getenv("DSB_FAULT_INJECTION");
    if (!mode) return false;
    std::fprintf(stderr,
                 "harness: DSB_FAULT_INJECTION=%s ignored: this build has no fault injection (configure with "
                 "-DDSB_FAULT_INJECTION=ON)\n",
                 mode);
    return true;
  }();
  (void)warned;
}
}  // namespace
#endif

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
  warn_if_requested();
  return -1;
#endif
}

void fault_maybe_kill(std::int64_t episodes) {
  const std::int64_t at = fault_kill_after_episodes();
  if (at >= 0 && episodes >= at) std::raise(SIGKILL);
}

int fault_signal_in_run(std::int64_t run_episodes) {
#ifdef DSB_FAULT_INJECTION
  struct Armed {
    std::int64_t at = -1;
    int sig = 0;
  };
  static const Armed armed = [] {
    const char* mode = std::getenv("DSB_FAULT_INJECTION");
    const char* at = std::getenv("DSB_FAULT_AT_EPISODE");
    const char* sig = std::getenv("DSB_FAULT_SIGNAL");
    if (!mode || std::strcmp(mode, "signal-in-run") != 0 || !at || !sig) return Armed{};
    const Armed a{std::atoll(at), std::atoi(sig)};
    std::fprintf(stderr, "harness: fault injection armed: signal %d when a run has %lld episodes\n", a.sig,
                 static_cast<long long>(a.at));
    return a;
  }();
  static std::atomic<bool> fired{false};
  if (armed.sig != 0 && run_episodes == armed.at && !fired.exchange(true)) return armed.sig;
#else
  (void)run_episodes;
  warn_if_requested();
#endif
  return 0;
}

void fault_raise(int sig) { std::raise(sig); }

bool fault_commit_every_episode() {
#ifdef DSB_FAULT_INJECTION
  static const bool every = [] {
    const char* v = std::getenv("DSB_FAULT_COMMIT_EVERY_EPISODE");
    return v && std::strcmp(v, "1") == 0;
  }();
  return every;
#else
  return false;
#endif
}

}  // namespace dsb
