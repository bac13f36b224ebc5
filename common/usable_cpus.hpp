#pragma once
// The number of CPUs this process may run on: the size of its affinity mask (sched_getaffinity),
// which honours taskset, cpusets and cgroups, and so Slurm's --cpus-per-task binding; falls back
// to std::thread::hardware_concurrency when the mask cannot be read.
#include <sched.h>

#include <algorithm>
#include <thread>

namespace dsb {

inline int usable_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return n;
  }
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace dsb
