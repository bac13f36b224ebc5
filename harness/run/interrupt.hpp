#pragma once
// SIGTERM (a Slurm time limit, `kill`), SIGINT (Ctrl-C) and SIGHUP (the terminal closed) ask the
// harness to stop: every run in progress finishes its current episode, commits what it has and
// stops; no new run starts; the harness says how to resume and exits 128 + the signal (143, 130,
// 129). A second signal of the same kind kills the
// process at once (the default action), for a user who will not wait for a long episode.
// External optimizers get TERM at once (ChildProcess::terminate_all) and are killed after
// ChildProcess::kStopGraceS seconds if still there; their runs commit and resume like the others.
#include <atomic>

namespace dsb {

// installs the handlers (idempotent)
void install_stop_handlers();

// set by the first SIGTERM or SIGINT
const std::atomic<bool>& stop_requested();

// the signal that asked to stop (SIGTERM, SIGINT or SIGHUP), 0 when none did
int stop_signal();

// for tests: as if `sig` had arrived
void request_stop(int sig);

}  // namespace dsb
