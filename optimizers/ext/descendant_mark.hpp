#pragma once
// Ending every descendant of an external optimizer with its run, detached ones included.
//
// The child runs in its own process group, and killing the group ends what it started the usual
// way. A descendant that detaches (setsid, a double fork, a daemon) leaves the group, and when
// its parent dies it leaves the child's tree too: neither the group nor the parent chain finds it
// any more. What it keeps is the environment it inherited. So every child gets one extra entry,
// its mark, DSB_EXT_RUN=<harness pid>.<serial>, unique to the child, and ending a run kills every
// process of ours whose environment (as /proc/PID/environ shows it: the one it was started with)
// holds that entry. A descendant that starts itself with an empty environment (env -i) escapes
// the mark; docs/ext-protocol.md says so.
#include <string>

namespace dsb {

// a new mark for a child about to start: "DSB_EXT_RUN=<pid>.<serial>", never the same twice in
// one process
std::string new_descendant_mark();

// SIGKILL to every process (but this one) whose environment holds the entry `mark` exactly,
// scanning /proc again until a scan finds none (a process may fork while it is being killed), at
// most 64 scans. Returns the number of processes killed. Async-signal-safe (raw system calls,
// fixed buffers, no allocation): the watchdog of a child calls it in a forked process.
int kill_marked_processes(const char* mark);

}  // namespace dsb
