#pragma once
// Fault injection for the interruption tests (test_harness_cli): makes the harness SIGKILL itself
// after a given number of episodes, so the tests can check that a killed grid resumes to the
// same database. It exists only in builds configured with DSB_FAULT_INJECTION=ON (the default
// only with DSB_BUILD_TESTS=ON) and fires only when both variables are set:
//   DSB_FAULT_INJECTION=kill-after-episodes  DSB_FAULT_KILL_AFTER_EPISODES=K
// A build without the option ignores both, so a stray variable cannot kill a production run; a
// build with it says so on stderr whenever the injection is armed.
#include <cstdint>

namespace dsb {

// the episode count after which to kill the process, or -1 when nothing is armed
std::int64_t fault_kill_after_episodes();

// kills the process (SIGKILL) when armed and `episodes` has reached the count
void fault_maybe_kill(std::int64_t episodes);

}  // namespace dsb
