// Fault injection in a build without it (harness/run/fault_injection.*): this test compiles that
// file on its own, without DSB_FAULT_INJECTION, as a production harness is built. Set variables must
// neither kill nor signal, and the build must say once that it ignores them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "harness/run/fault_injection.hpp"

namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(FaultInjectionOff, VariablesAreIgnoredWithOneWarning) {
#ifdef DSB_FAULT_INJECTION
  FAIL() << "this test must be compiled without DSB_FAULT_INJECTION";
#endif
  ::setenv("DSB_FAULT_INJECTION", "kill-after-episodes", 1);
  ::setenv("DSB_FAULT_KILL_AFTER_EPISODES", "0", 1);
  ::setenv("DSB_FAULT_AT_EPISODE", "3", 1);
  ::setenv("DSB_FAULT_SIGNAL", "9", 1);
  ::setenv("DSB_FAULT_COMMIT_EVERY_EPISODE", "1", 1);
  testing::internal::CaptureStderr();
  EXPECT_EQ(dsb::fault_kill_after_episodes(), -1);
  dsb::fault_maybe_kill(1000);  // would SIGKILL this test in a build with the option
  for (std::int64_t episode = 0; episode < 10; ++episode) EXPECT_EQ(dsb::fault_signal_in_run(episode), 0);
  EXPECT_FALSE(dsb::fault_commit_every_episode());
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(count(err, "harness: DSB_FAULT_INJECTION=kill-after-episodes ignored: this build has no fault injection"),
            1)
      << err;
  EXPECT_EQ(count(err, "\n"), 1) << err;
}

}  // namespace
