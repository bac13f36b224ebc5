#pragma once
// Test helper: runs the real `harness` program through the shell, as a user does, and captures
// its exit code, stdout and stderr (files under `dir`).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace dsb::testing {

struct HarnessResult {
  int code;
  std::string out, err;
};

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// env_prefix may set variables ("A=1 B=2")
inline HarnessResult run_harness(const std::filesystem::path& dir, const std::string& args,
                                 const std::string& env_prefix = "") {
  const auto out = dir / "stdout", err = dir / "stderr";
  const std::string cmd = env_prefix + " " + DSB_HARNESS_EXE + " " + args + " > " + out.string() + " 2> " +
                          err.string() + " < /dev/null";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_file(out), read_file(err)};
}

}  // namespace dsb::testing
