#pragma once
// Fault injection for the interruption tests (test_harness_cli): makes the harness SIGKILL itself
// after a given number of episodes, so the tests can check that a killed grid resumes to the
// same database. It exists only in builds configured with DSB_FAULT_INJECTION=ON (the default
// only with DSB_BUILD_TESTS=ON) and fires only when both variables are set:
//   DSB_FAULT_INJECTION=kill-after-episodes  DSB_FAULT_KILL_AFTER_EPISODES=K
// and, for mid-run interruptions (a run stopped after a given episode of its own):
//   DSB_FAULT_INJECTION=signal-in-run  DSB_FAULT_AT_EPISODE=K  DSB_FAULT_SIGNAL=15 (TERM) or 9 (KILL)
// (the first run to record its K-th episode commits it, then raises the signal), and
//   DSB_FAULT_COMMIT_EVERY_EPISODE=1 (commit after every episode instead of every few seconds).
// A build without the option ignores all of them, so a stray variable cannot kill a production run,
// and says once on stderr that DSB_FAULT_INJECTION is ignored; a build with it says so on stderr
// whenever the injection is armed (test_fault_injection_off checks the first).
#include <cstdint>

namespace dsb {

// the episode count after which to kill the process, or -1 when nothing is armed
std::int64_t fault_kill_after_episodes();

// kills the process (SIGKILL) when armed and `episodes` has reached the count
void fault_maybe_kill(std::int64_t episodes);

// signal-in-run: the signal to raise once a run has recorded `run_episodes` episodes (after
// committing them), or 0
int fault_signal_in_run(std::int64_t run_episodes);
void fault_raise(int sig);

// DSB_FAULT_COMMIT_EVERY_EPISODE
bool fault_commit_every_episode();

}  // namespace dsb
