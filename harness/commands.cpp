#include "harness/commands.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/unit_box.hpp"
#include "envs/registry.hpp"
#include "harness/output_path.hpp"
#include "optimizers/registry.hpp"

namespace dsb {

std::vector<double> parse_number_list(const std::string& option, const std::string& text) {
  std::vector<double> values;
  std::size_t pos = 0;
  while (true) {
    const std::size_t comma = text.find(',', pos);
    std::string token = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    // trim spaces
    const auto first = token.find_first_not_of(" \t");
    const auto last = token.find_last_not_of(" \t");
    token = first == std::string::npos ? "" : token.substr(first, last - first + 1);
    double v = 0.0;
    const char* begin = token.data();
    const char* end = token.data() + token.size();
    if (!token.empty() && *begin == '+') ++begin;
    const auto [ptr, ec] = std::from_chars(begin, end, v);
    if (token.empty() || ec != std::errc() || ptr != end || !std::isfinite(v))
      throw UsageError(option + ": '" + token + "' is not a finite number");
    values.push_back(v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return values;
}

int command_list() {
  std::cout << fmt::format("{:<22} {:>5} {:>14} {:>3}  {}\n", "env", "dim", "differentiable", "rl",
                           "description");
  for (const auto& family : env_families()) {
    for (const auto& name : family.grid_names) {
      const EnvInfo& info = shared_env(name)->info();  // metadata only: no model is built
      std::cout << fmt::format("{:<22} {:>5} {:>14} {:>3}  {}\n", name, info.dim,
                               info.differentiable ? "yes" : "no", info.rl ? "yes" : "no",
                               family.pattern == name ? family.description
                                                      : family.pattern + ": " + family.description);
    }
  }
  std::cout << "\n"
            << fmt::format("{:<22} {:>14} {:>8} {:>9}  {}\n", "optimizer", "needs gradient", "needs rl", "seed use",
                           "description");
  const auto seed_use = [](SeedUse u) { return u == SeedUse::never ? "never" : u == SeedUse::late ? "late" : "at start"; };
  for (const auto& e : optimizer_entries())
    std::cout << fmt::format("{:<22} {:>14} {:>8} {:>9}  {}\n", e.name, e.needs_gradient ? "yes" : "no",
                             e.needs_rl ? "yes" : "no", seed_use(e.seed_use), e.description);
  std::cout << fmt::format("{:<22} {:>14} {:>8} {:>9}  {}\n", "ext:NAME", "either", "no", "its own",
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
  return 0;
}

std::vector<double> checked_point(const Env& env, const std::string& x_text, const std::string& option) {
  const auto x = parse_number_list(option, x_text);
  if (static_cast<int>(x.size()) != env.dim())
    throw UsageError(fmt::format("{} has {} values, env '{}' needs {}", option, x.size(), env.name(), env.dim()));
  if (const auto i = first_outside_box(x); i >= 0)
    throw UsageError(fmt::format("{}: value {} at position {} is outside [-1, 1]", option, x[i], i));
  return x;
}

namespace {

// JSON number, or null for NaN/Inf (JSON has neither)
nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

int command_eval(const std::string& env_name, const std::string& x_text, bool with_grad, const EnvOptions& options) {
  const auto env = make_env(env_name, options);
  const auto x = checked_point(*env, x_text);
  if (with_grad && !env->differentiable())
    throw UsageError("--grad: env '" + env_name + "' is not differentiable");
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

int command_landscape(const std::string& env_name, const std::string& dims, int resolution,
                      const std::string& center, const std::string& out_path,
                      const std::optional<GradientCheckOptions>& check, bool force) {
  const auto env = make_env(env_name);
  const int n = env->dim();
  const auto d = parse_number_list("--dims", dims);
  if (d.size() != 2 || d[0] != std::floor(d[0]) || d[1] != std::floor(d[1]) || d[0] < 0 || d[1] < 0 ||
      d[0] >= n || d[1] >= n || d[0] == d[1])
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
        out << num(r.loss) << ',' << num(ci.analytic) << ',' << num(cj.analytic) << ','
            << num(ci.differences.central) << ',' << num(cj.differences.central) << ','
            << num(r.worst_relative_error) << ',' << (agrees ? 1 : 0) << '\n';
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
    std::cerr << fmt::format("harness: the gradient along dims {}, {} agrees with central differences (step {:g}, "
                             "tolerance {:g}) at {} of {} points ({:.1f}%)\n",
                             i, j, check->step, check->tolerance, agreeing, resolution * resolution,
                             100.0 * agreeing / (resolution * resolution));
  if (check && compared > 0)
    std::cerr << fmt::format("harness: its direction in the slice is within 25 degrees of the differences' at {} "
                             "({:.1f}%) and opposed (cos < 0) at {} ({:.1f}%) of {} points with both nonzero\n",
                             aligned, 100.0 * aligned / compared, opposed, 100.0 * opposed / compared, compared);
  return 0;
}

}  // namespace dsb
