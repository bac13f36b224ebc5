#pragma once
// The memory this process may use: the machine's physical memory, or less where a control group
// limits it (a container, a Slurm job's --mem): cgroup v2's memory.max or cgroup v1's
// memory.limit_in_bytes of the process's own group (/proc/self/cgroup), read once per call.
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <string>

namespace dsb {

namespace detail {

// a limit in bytes from a cgroup file ("max" or an absurd value: none)
inline std::uint64_t cgroup_limit(const std::string& file) {
  std::ifstream in(file);
  std::string text;
  if (!(in >> text) || text == "max") return UINT64_MAX;
  try {
    return std::stoull(text);
  } catch (...) {
    return UINT64_MAX;
  }
}

}  // namespace detail

inline std::uint64_t usable_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  std::uint64_t limit =
      pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : UINT64_MAX;
  // /proc/self/cgroup: "0::PATH" (v2) or "N:memory:PATH" (v1)
  std::ifstream groups("/proc/self/cgroup");
  for (std::string line; std::getline(groups, line);) {
    const auto first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1), path = line.substr(second + 1);
    if (controllers.empty()) {
      limit = std::min({limit, detail::cgroup_limit("/sys/fs/cgroup" + path + "/memory.max"),
                        detail::cgroup_limit("/sys/fs/cgroup/memory.max")});
    } else if (controllers == "memory") {
      limit = std::min({limit, detail::cgroup_limit("/sys/fs/cgroup/memory" + path + "/memory.limit_in_bytes"),
                        detail::cgroup_limit("/sys/fs/cgroup/memory/memory.limit_in_bytes")});
    }
  }
  return limit;
}

}  // namespace dsb
