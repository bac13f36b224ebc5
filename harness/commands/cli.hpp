#pragma once
// Command line of the `harness` program. Returns the exit code (docs/commands.md "Reliability"):
//   0    success; for a grid: every run of it is done
//   1    a check failed, or a runtime error (a store that cannot be written, a failed report)
//   2    bad input: one line on stderr naming the bad value; nothing stored is touched
//   3    a grid ended with failed runs (their count on stderr; each is stored with its error,
//        `harness plan --db` lists them, and they run again next time)
//   128+N  stopped by signal N (143 SIGTERM, 130 SIGINT, 129 SIGHUP): the same command resumes
namespace dsb {

inline constexpr int kExitRunsFailed = 3;

int harness_main(int argc, char** argv);

}  // namespace dsb
