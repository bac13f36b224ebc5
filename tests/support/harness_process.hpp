#pragma once
// Test helper: runs the real `harness` program through the shell, as a user does, and captures
// its exit code, stdout and stderr (files under `dir`); or starts it in the background and waits
// for a state of its database.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include "sqlite_rows.hpp"

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
  const std::string cmd =
      env_prefix + " " + DSB_HARNESS_EXE + " " + args + " > " + out.string() + " 2> " + err.string() + " < /dev/null";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_file(out), read_file(err)};
}

// Starts `sh -c "exec PREFIX harness ARGS"` in the background (output to /dev/null unless ARGS
// redirect it); the caller waits for it (waitpid) or kills it.
inline pid_t start_harness(const std::string& args, const std::string& env_prefix = "") {
  const std::string cmd = env_prefix + " exec " + DSB_HARNESS_EXE + " " + args + " > /dev/null 2>&1 < /dev/null";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

// Polls `sql` on the database at `path` until it returns `want`; false when the process `pid`
// exits first (it is then reaped) or `timeout` passes (a generous bound, not a timing assertion).
inline bool wait_until(const std::string& path, const std::string& sql, const std::string& want, pid_t pid,
                       std::chrono::seconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (std::filesystem::exists(path) && quiet_scalar(path, sql) == want) return true;
    if (::waitpid(pid, nullptr, WNOHANG) != 0) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

}  // namespace dsb::testing
