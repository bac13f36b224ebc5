#pragma once
// Command line of the `harness` program (contract in design.md). Returns the exit code:
// 0 success, 1 a check failed or a run command hit a runtime error, 2 bad input (one line on
// stderr naming the bad value; nothing stored is touched).
namespace dsb {

int harness_main(int argc, char** argv);

}  // namespace dsb
