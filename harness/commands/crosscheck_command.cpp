// `harness crosscheck`: the rigid envs' forward dynamics against MuJoCo and Bullet (reference/).
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/error.hpp"
#include "harness/commands/command.hpp"
#include "reference/crosscheck.hpp"

namespace dsb {

Command crosscheck_command() {
  return {
      "crosscheck", "in-house vs MuJoCo vs Bullet: table of deviations", [](CLI::App& app) {
        auto envs = std::make_shared<std::vector<std::string>>();
        app.add_option("--env", *envs, "rigid envs, comma-separated (default: all five)")->delimiter(',');
        return [envs] {
          if (!crosscheck_available())
            throw UsageError("crosscheck: this build has neither MuJoCo nor Bullet (DSB_WITH_MUJOCO, DSB_WITH_BULLET)");
          return run_crosscheck(*envs, std::cout);
        };
      }};
}

}  // namespace dsb
