#include "harness/commands/cli.hpp"

#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "common/error.hpp"
#include "common/shown_value.hpp"
#include "common/simd_path.hpp"
#include "git_sha.hpp"  // generated: DSB_GIT_SHA
#include "harness/commands/command.hpp"

namespace dsb {
namespace {

// a message as one line with no control character: what it echoes from the user (a path with a
// newline or an escape sequence) shows as escapes and cannot forge lines or drive the terminal
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return shown_value(s);
}

}  // namespace

int harness_main(int argc, char** argv) {
  CLI::App app{"diffsim-bench harness: optimizers x differentiable simulators, every episode in SQLite"};
  app.set_version_flag("--version",
                       fmt::format("harness {} (git {}, {} build)", DSB_VERSION, DSB_GIT_SHA, DSB_BUILD_TYPE));
  app.require_subcommand(0, 1);
  // bare flags are `run`'s (harness --all --seeds 5)
  const std::function<int()> bare_run = run_command().define(app);
  std::vector<std::pair<CLI::App*, std::function<int()>>> commands;
  for (const Command& c : harness_commands()) {
    CLI::App* sub = app.add_subcommand(c.name, c.help);
    commands.emplace_back(sub, c.define(*sub));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "harness: error: %s\n", one_line(e.what()).c_str());
    return 2;
  }

  // the kernel path the environment may force (DSB_SIMD; common/simd_path.hpp, docs/determinism.md):
  // a bad value stops the command here, before anything is stored, rather than failing each run
  try {
    (void)simd_ceiling();
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "harness: error: %s\n", one_line(e.what()).c_str());
    return 2;
  }

  try {
    for (const auto& [sub, action] : commands)
      if (sub->parsed()) return action();
    return bare_run();
  } catch (const UsageError& e) {
    std::fprintf(stderr, "harness: error: %s\n", one_line(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harness: failed: %s\n", one_line(e.what()).c_str());
    return 1;
  }
}

}  // namespace dsb
