#include "harness/run/interrupt.hpp"

#include <csignal>

#include "optimizers/ext/child_process.hpp"

namespace dsb {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "the handler touches only lock-free atomics (async-signal-safe)");

extern "C" void on_stop_signal(int sig) {
  if (g_stop.load()) {
    // the second signal: the default action (terminate) now
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_signal.store(sig);
  g_stop.store(true);
  ChildProcess::terminate_all();  // external optimizers hear it now, not after their reply
}

}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // interrupted system calls go on; the workers poll the flag between episodes
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);  // a closed terminal or ssh session: the same orderly stop
}

const std::atomic<bool>& stop_requested() { return g_stop; }

int stop_signal() { return g_signal.load(); }

void request_stop(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
  ChildProcess::terminate_all();
}

}  // namespace dsb
