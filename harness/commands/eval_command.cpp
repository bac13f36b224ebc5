// `harness eval`: one rollout of an env at x, JSON on stdout.
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
#include "optimizers/registry.hpp"
#include "envs/core/env_options.hpp"
#include "harness/plan/grid.hpp"

namespace dsb {
namespace {

// JSON number, or null for NaN/Inf (JSON has neither)
nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

int command_eval(const std::string& env_name, const std::string& x_text, bool with_grad, const EnvOptions& options) {
  const auto env = make_env(env_name, options);
  const auto x = checked_point(*env, x_text);
  if (with_grad && !env->differentiable()) throw UsageError("--grad: env '" + env_name + "' is not differentiable");
  nlohmann::json out = {{"env", env_name}, {"x", x}};
  const auto ws = env->make_workspace();
  if (with_grad) {
    std::vector<double> grad(env->dim());
    out["loss"] = number(env->loss_and_grad(x, grad, *ws, serial_team()));
    nlohmann::json g = nlohmann::json::array();
    for (double v : grad) g.push_back(number(v));
    out["grad"] = g;
  } else {
    out["loss"] = number(env->loss(x, *ws, serial_team()));
  }
  // the env's second metric, when it has one (e.g. "metric": {"soft_iou": 0.71})
  if (!env->info().metric.empty()) out["metric"] = {{env->info().metric, number(env->episode_metric(*ws))}};
  std::cout << out.dump() << "\n";
  return 0;
}

}  // namespace

Command eval_command() {
  return {"eval", "one rollout at x, JSON on stdout", [](CLI::App& app) {
            struct Args {
              std::string env, x;
              std::vector<std::string> sets;
              bool grad = false;
            };
            auto a = std::make_shared<Args>();
            app.add_option("--env", a->env, "env name")->required();
            app.add_option("--set", a->sets,
                           "an option of the env, ENV.KEY=VALUE (repeatable; `harness list` shows them)")
                ->type_name("ENV.KEY=VALUE");
            app.add_option("--x", a->x, "comma-separated parameters in [-1, 1]")->required();
            app.add_flag("--grad", a->grad, "also print dLoss/dx (normalized units)");
            return [a] { return command_eval(a->env, a->x, a->grad, parse_env_settings(a->env, a->sets)); };
          }};
}

}  // namespace dsb
