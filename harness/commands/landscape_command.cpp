// `harness landscape`: loss and gradient on an N x N grid over a 2-D slice of the box, as CSV.
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

namespace dsb {
namespace {

int command_landscape(const std::string& env_name, const std::string& dims, int resolution, const std::string& center,
                      const std::string& out_path, const std::optional<GradientCheckOptions>& check, bool force) {
  const auto env = make_env(env_name);
  const int n = env->dim();
  const auto d = parse_number_list("--dims", dims);
  if (d.size() != 2 || d[0] != std::floor(d[0]) || d[1] != std::floor(d[1]) || d[0] < 0 || d[1] < 0 || d[0] >= n ||
      d[1] >= n || d[0] == d[1])
    throw UsageError(fmt::format("--dims: '{}' must be two different indices in 0..{}", dims, n - 1));
  if (resolution < 2 || resolution > 2000)
    throw UsageError(fmt::format("--res must be in 2..2000, got {}", resolution));
  if (check) {
    if (!env->differentiable()) throw UsageError("--check-step: env '" + env_name + "' has no gradient to check");
    try {
      check->validate();
    } catch (const ConfigError& e) {
      throw UsageError(std::string("--check-step/--tol: ") + e.what());
    }
  }
  std::vector<double> x(n, 0.0);
  if (!center.empty()) x = checked_point(*env, center, "--center");
  OutputFile file("--out", out_path, force);
  std::ofstream& out = file.stream();
  const int i = static_cast<int>(d[0]), j = static_cast<int>(d[1]);
  const int slice[2] = {i, j};
  int agreeing = 0, aligned = 0, opposed = 0, compared = 0;
  out << "i,j,xi,xj,loss,grad_i,grad_j" << (check ? ",fd_i,fd_j,rel_err,agrees" : "") << "\n";
  std::vector<double> grad(n);
  const auto ws = env->make_workspace();  // one workspace for every grid point
  auto num = [](double v) { return std::isfinite(v) ? fmt::format("{:.17g}", v) : std::string("nan"); };
  for (int a = 0; a < resolution; ++a) {
    for (int b = 0; b < resolution; ++b) {
      // grid over [-1, 1]: endpoints included
      x[i] = -1.0 + 2.0 * a / (resolution - 1);
      x[j] = -1.0 + 2.0 * b / (resolution - 1);
      out << a << ',' << b << ',' << num(x[i]) << ',' << num(x[j]) << ',';
      if (check) {
        // the point's loss and gradient, and central differences along i and j (loss() path)
        const GradientCheckResult r = check_gradient_along(*env, *ws, x, slice, *check);
        const auto& ci = r.coordinates[0];
        const auto& cj = r.coordinates[1];
        const bool agrees = r.passed;
        agreeing += agrees;
        // the slice's 2-D gradient against the differences' direction
        if (!std::isnan(r.direction_cosine)) {
          ++compared;
          aligned += r.direction_cosine > kAlignedCosine;
          opposed += r.direction_cosine < 0.0;
        }
        out << num(r.loss) << ',' << num(ci.analytic) << ',' << num(cj.analytic) << ',' << num(ci.differences.central)
            << ',' << num(cj.differences.central) << ',' << num(r.worst_relative_error) << ',' << (agrees ? 1 : 0)
            << '\n';
      } else if (env->differentiable()) {
        const double loss = env->loss_and_grad(x, grad, *ws, serial_team());
        out << num(loss) << ',' << num(grad[i]) << ',' << num(grad[j]) << '\n';
      } else {
        out << num(env->loss(x, *ws, serial_team())) << ",,\n";
      }
    }
  }
  file.commit();
  std::cerr << fmt::format("harness: wrote {} grid points of {} (dims {}, {}) to {}\n", resolution * resolution,
                           env_name, i, j, out_path);
  if (check)
    std::cerr << fmt::format(
        "harness: the gradient along dims {}, {} agrees with central differences (step {:g}, "
        "tolerance {:g}) at {} of {} points ({:.1f}%)\n",
        i, j, check->step, check->tolerance, agreeing, resolution * resolution,
        100.0 * agreeing / (resolution * resolution));
  if (check && compared > 0)
    std::cerr << fmt::format(
        "harness: its direction in the slice is within 25 degrees of the differences' at {} "
        "({:.1f}%) and opposed (cos < 0) at {} ({:.1f}%) of {} points with both nonzero\n",
        aligned, 100.0 * aligned / compared, opposed, 100.0 * opposed / compared, compared);
  return 0;
}

}  // namespace

Command landscape_command() {
  return {"landscape", "loss and gradient on an N x N grid over a 2-D slice", [](CLI::App& app) {
            struct Args {
              std::string env, dims, center, out;
              int res = 0;
              bool force = false;
              GradientCheckOptions check;
            };
            auto a = std::make_shared<Args>();
            a->check.step = 0.0;
            app.add_option("--env", a->env, "env name")->required();
            app.add_option("--dims", a->dims, "the two coordinates of the slice, I,J (0-based)")->required();
            app.add_option("--res", a->res, "grid points per axis, N")->required();
            app.add_option("--center", a->center, "comma-separated point for the other coordinates (default 0)");
            app.add_option("--out", a->out, "CSV file to write (a new file; see --force)")->required();
            app.add_flag("--force", a->force, "write over an existing file (never over a database)");
            CLI::Option* check_step =
                app.add_option("--check-step", a->check.step,
                               "also check both gradient components against central differences with this step");
            app.add_option("--tol", a->check.tolerance, "largest accepted relative error of the check (default 1e-4)");
            return [a, check_step] {
              return command_landscape(a->env, a->dims, a->res, a->center, a->out,
                                       check_step->count() > 0 ? std::optional(a->check) : std::nullopt, a->force);
            };
          }};
}

}  // namespace dsb
