#pragma once
// Peak resident memory of a piece of work run alone in a forked child process: what a process
// that only builds an env and runs one episode needs (the bench process itself holds more).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "common/parallel.hpp"
#include "envs/registry.hpp"

namespace dsb::perf {

// MB (ru_maxrss of the child); `work` returns whether it succeeded (the child's exit status)
inline double child_peak_rss_mb(const std::function<bool()>& work) {
  const pid_t pid = fork();
  if (pid == 0) _exit(work() ? 0 : 1);
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  return ru.ru_maxrss / 1024.0;
}

// the same for building env `env_name` and running one gradient episode at point(dim), keeping
// up to tape_memory_bytes of its forward pass (Workspace::tape_memory_bytes)
inline double gradient_episode_peak_rss_mb(const std::string& env_name,
                                           const std::function<std::vector<double>(int dim)>& point,
                                           std::size_t tape_memory_bytes = 0) {
  return child_peak_rss_mb([&] {
    const auto env = make_env(env_name);
    const auto x = point(env->dim());
    std::vector<double> g(x.size());
    const auto ws = env->make_workspace();
    ws->tape_memory_bytes = tape_memory_bytes;
    return std::isfinite(env->loss_and_grad(x, g, *ws, serial_team()));
  });
}

}  // namespace dsb::perf
