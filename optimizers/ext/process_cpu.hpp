#pragma once
// The CPU an external optimizer's processes spent, for a run's runs.cpu_s. Two readings:
// - while the program runs: the sum, over every live process of its process group (the shell of
//   `/bin/sh -c`, the program, what they started), of its own CPU and that of its children it
//   has waited for (utime + stime + cutime + cstime of /proc/PID/stat, in clock ticks: 10 ms on
//   Linux's usual USER_HZ of 100);
// - once it is reaped: wait4's rusage (user + system), its own CPU and that of every descendant
//   it waited for, in microseconds.
// Not counted: a descendant that left the group (setsid) or was never waited for.
#include <sys/resource.h>
#include <sys/types.h>

namespace dsb {

// the CPU seconds of the live processes of group `pgid` (see above); 0 when none is left
double process_group_cpu_seconds(pid_t pgid);

// user + system seconds of an rusage
double rusage_cpu_seconds(const rusage& usage);

}  // namespace dsb
