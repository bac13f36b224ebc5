// `harness list`: the envs (dim, differentiable, rl), the optimizers, the env options and the knobs.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/unit_box.hpp"
#include "envs/core/gradient_check.hpp"
#include "envs/registry.hpp"
#include "harness/commands/command.hpp"
#include "harness/core/output_path.hpp"
#include "harness/commands/point_text.hpp"
#include "harness/core/results_versions.hpp"
#include "optimizers/registry.hpp"

namespace dsb {
namespace {

int command_list() {
  // version: the results version (harness/core/results_versions.hpp), part of every run key
  std::cout << fmt::format("{:<22} {:>7} {:>5} {:>14} {:>3}  {}\n", "env", "version", "dim", "differentiable", "rl",
                           "description");
  for (const auto& family : env_families()) {
    for (const auto& name : family.grid_names) {
      const EnvInfo& info = shared_env(name)->info();  // metadata only: no model is built
      std::cout << fmt::format(
          "{:<22} {:>7} {:>5} {:>14} {:>3}  {}\n", name, family.results_version, info.dim,
          info.differentiable ? "yes" : "no", info.rl ? "yes" : "no",
          family.pattern == name ? family.description : family.pattern + ": " + family.description);
    }
  }
  std::cout << "\n"
            << fmt::format("{:<22} {:>7} {:>14} {:>8} {:>9}  {}\n", "optimizer", "version", "needs gradient",
                           "needs rl", "seed use", "description");
  const auto seed_use = [](SeedUse u) {
    return u == SeedUse::never ? "never" : u == SeedUse::late ? "late" : "at start";
  };
  for (const auto& e : optimizer_entries())
    std::cout << fmt::format("{:<22} {:>7} {:>14} {:>8} {:>9}  {}\n", e.name, e.results_version,
                             e.needs_gradient ? "yes" : "no", e.needs_rl ? "yes" : "no", seed_use(e.seed_use),
                             e.description);
  std::cout << fmt::format("{:<22} {:>7} {:>14} {:>8} {:>9}  {}\n", "ext:NAME", kExtResultsVersion, "either", "no",
                           "its own",
                           "your own optimizer, a program on the process protocol: --ext NAME='COMMAND' "
                           "(docs/ext-protocol.md)");
  std::cout << "\nenv options (--set ENV.KEY=VALUE with ENV a name of the family, e.g. plb-pinch-h5.target=F.npy; "
               "also `harness eval --set`; another value is another env config, so its own runs)\n";
  for (const auto& family : env_families())
    for (const auto& o : family.options)
      std::cout << fmt::format("{:<22} {:<8} {}; default: {}\n", family.pattern, o.key, o.meaning, o.default_text);
  std::cout << "\nknobs (--set OPTIMIZER.KNOB=VALUE; a variant is its own run)\n";
  for (const auto& e : optimizer_entries())
    if (!e.knobs.empty()) std::cout << fmt::format("{:<22} {}\n", e.name, fmt::join(e.knobs, ", "));
  std::cout << "\nresults versions: each env's and optimizer's above, and the run code's (budget wrapper, replay, "
               "seeding); a stored run of other versions is stale (docs/database.md)\n";
  std::cout << fmt::format("run code version {}\n", kRunCodeResultsVersion);
  return 0;
}

}  // namespace

Command list_command() {
  return {"list", "envs (dim, differentiable, rl) and optimizers",
          [](CLI::App&) { return [] { return command_list(); }; }};
}

}  // namespace dsb
