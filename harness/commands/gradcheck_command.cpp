// `harness gradcheck`: the gradient survey of envs/core/gradient_check.hpp as a per-point table and
// a summary, or as one JSON object; with --large-step H (default 0.05, 0 = off) the summary also
// says how often a central difference of step H along the gradient contradicts its direction.
#include <cmath>
#include <iostream>
#include <string>

#include <memory>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "envs/registry.hpp"
#include "envs/core/gradient_check.hpp"
#include "harness/commands/command.hpp"

namespace dsb {
namespace {

// JSON number, or null for NaN/Inf (JSON has neither)
nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

// what went wrong at a point, then what is notable; "ok" first when nothing went wrong
std::string status(const GradientCheckResult& r) {
  std::string s = r.passed ? "ok" : "FAIL";
  if (!r.finite) s += " non-finite";
  if (!r.value_agrees) s += " value-mismatch";
  if (r.finite && !r.gradient_agrees) s += " disagrees";
  if (r.exactly_zero) s += " zero";
  if (r.bit_equal_to_differences) s += " bit-equal-to-fd";
  return s;
}

std::string percent(int count, int total) { return fmt::format("{:5.1f}%", 100.0 * count / total); }

void print_table(const std::string& env_name, int dim, const GradientSurveyOptions& o, const GradientSurvey& s) {
  const auto& c = o.check;
  std::cout << fmt::format(
      "gradcheck {} (dim {}): central differences with step {}, points uniform in "
      "[-{}, {}]^{}, seed {}\n",
      env_name, dim, c.step, o.amplitude, o.amplitude, dim, o.seed);
  std::cout << fmt::format("{:>5} {:>14} {:>12} {:>12} {:>12} {:>12} {:>6} {:>8}  {}\n", "point", "loss", "|grad|",
                           "max|fd|", "max abs err", "max rel err", "coord", "cos", "status");
  for (int p = 0; p < s.points; ++p) {
    const auto& r = s.checks[p];
    std::cout << fmt::format("{:>5} {:>14.6e} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e} {:>6} {:>8.4f}  {}\n", p, r.loss,
                             r.gradient_norm, r.max_abs_central, r.worst_absolute_error, r.worst_relative_error,
                             r.worst_coordinate, r.direction_cosine, status(r));
  }
  const int n = s.points;
  std::cout << fmt::format(
      "\nsummary over {} points (relative error |grad - fd| / (|fd| + {} max|fd| + {}), "
      "tolerance {:.1e}):\n",
      n, c.relative_floor, c.absolute_floor, c.tolerance);
  std::cout << fmt::format("  {:<42} {:>6} of {:<6} {}\n", "gradient agrees with central differences", s.agreeing, n,
                           percent(s.agreeing, n));
  if (s.directed > 0) {
    std::cout << fmt::format("  {:<42} {:>6} of {:<6} {}\n", "gradient within 25 degrees of differences", s.aligned,
                             s.directed, percent(s.aligned, s.directed));
    std::cout << fmt::format("  {:<42} {:>6} of {:<6} {}\n", "gradient opposed to differences (cos < 0)", s.opposed,
                             s.directed, percent(s.opposed, s.directed));
  }
  std::cout << fmt::format("  {:<42} {:>6} of {:<6} {}\n", "gradient exactly zero", s.exactly_zero, n,
                           percent(s.exactly_zero, n));
  std::cout << fmt::format("  {:<42} {:>6} of {}\n", "non-finite loss, gradient or difference", s.non_finite, n);
  std::cout << fmt::format("  {:<42} {:>6} of {}\n", "loss() != loss_and_grad() at x", s.value_mismatches, n);
  std::cout << fmt::format("  {:<42} {:>6} of {}\n", "gradient bit-equal to central differences",
                           s.bit_equal_to_differences, n);
  if (!s.large_steps.empty()) {
    const auto title = fmt::format("opposed to a step-{} difference along it", o.large_step);
    std::cout << fmt::format("  {:<42} {:>6} of {:<6} {}\n", title, s.large_step_opposed, s.large_step_directed,
                             s.large_step_directed > 0 ? percent(s.large_step_opposed, s.large_step_directed) : "  -");
    const auto& r = s.large_step_ratio;
    std::cout << fmt::format("  {:<42} min {:.4e}  q1 {:.4e}  median {:.4e}  q3 {:.4e}  max {:.4e}\n",
                             "step-difference along it / |grad|", r.min, r.q1, r.median, r.q3, r.max);
  }
  const auto& q = s.gradient_norm;
  std::cout << fmt::format("  {:<42} min {:.4e}  q1 {:.4e}  median {:.4e}  q3 {:.4e}  max {:.4e}\n", "|grad|", q.min,
                           q.q1, q.median, q.q3, q.max);
  std::cout << fmt::format("  {:<42} loss() {:.3e} s, loss_and_grad() {:.3e} s (ratio {:.2f})\n", "time per call",
                           s.seconds_per_loss, s.seconds_per_loss_and_grad,
                           s.seconds_per_loss / s.seconds_per_loss_and_grad);
  std::cout << fmt::format(
      "gradcheck {}: {} points, worst relative error {:.3e} at point {} coordinate {} "
      "(tolerance {:.1e}): {}\n",
      env_name, n, s.worst_relative_error, s.worst_point, s.worst_coordinate, c.tolerance, s.passed ? "PASS" : "FAIL");
}

nlohmann::json to_json(const std::string& env_name, int dim, const GradientSurveyOptions& o, const GradientSurvey& s) {
  const auto& c = o.check;
  nlohmann::json points = nlohmann::json::array();
  for (int p = 0; p < s.points; ++p) {
    const auto& r = s.checks[p];
    points.push_back({{"index", p},
                      {"x", s.x[p]},
                      {"loss", number(r.loss)},
                      {"value_path_loss", number(r.value_path_loss)},
                      {"value_agrees", r.value_agrees},
                      {"gradient_norm", number(r.gradient_norm)},
                      {"max_abs_central", number(r.max_abs_central)},
                      {"worst_absolute_error", number(r.worst_absolute_error)},
                      {"worst_relative_error", number(r.worst_relative_error)},
                      {"worst_coordinate", r.worst_coordinate},
                      {"finite", r.finite},
                      {"exactly_zero", r.exactly_zero},
                      {"bit_equal_to_differences", r.bit_equal_to_differences},
                      {"gradient_agrees", r.gradient_agrees},
                      {"direction_cosine", number(r.direction_cosine)},
                      {"passed", r.passed}});
    if (!s.large_steps.empty()) {
      const auto& l = s.large_steps[p];
      points.back()["large_step"] = {
          {"directed", l.directed},   {"lo", l.lo},           {"hi", l.hi},    {"difference", number(l.difference)},
          {"ratio", number(l.ratio)}, {"opposed", l.opposed}, {"flat", l.flat}};
    }
  }
  const auto& q = s.gradient_norm;
  const int n = s.points;
  nlohmann::json summary = {{"points", n},
                            {"agreeing", s.agreeing},
                            {"agreeing_fraction", static_cast<double>(s.agreeing) / n},
                            {"aligned", s.aligned},
                            {"opposed", s.opposed},
                            {"directed", s.directed},
                            {"exactly_zero", s.exactly_zero},
                            {"exactly_zero_fraction", static_cast<double>(s.exactly_zero) / n},
                            {"non_finite", s.non_finite},
                            {"value_mismatches", s.value_mismatches},
                            {"bit_equal_to_differences", s.bit_equal_to_differences},
                            {"gradient_norm",
                             {{"min", number(q.min)},
                              {"q1", number(q.q1)},
                              {"median", number(q.median)},
                              {"q3", number(q.q3)},
                              {"max", number(q.max)}}},
                            {"worst_relative_error", number(s.worst_relative_error)},
                            {"worst_point", s.worst_point},
                            {"worst_coordinate", s.worst_coordinate},
                            {"seconds_per_loss", s.seconds_per_loss},
                            {"seconds_per_loss_and_grad", s.seconds_per_loss_and_grad},
                            {"passed", s.passed}};
  if (!s.large_steps.empty()) {
    const auto& r = s.large_step_ratio;
    summary["large_step_directed"] = s.large_step_directed;
    summary["large_step_opposed"] = s.large_step_opposed;
    summary["large_step_flat"] = s.large_step_flat;
    summary["large_step_opposed_fraction"] = s.large_step_directed > 0
        ? nlohmann::json(static_cast<double>(s.large_step_opposed) / s.large_step_directed)
        : nlohmann::json();
    summary["large_step_ratio"] = {{"min", number(r.min)},
                                   {"q1", number(r.q1)},
                                   {"median", number(r.median)},
                                   {"q3", number(r.q3)},
                                   {"max", number(r.max)}};
  }
  return {{"env", env_name},
          {"dim", dim},
          {"options",
           {{"points", o.points},
            {"seed", o.seed},
            {"amplitude", o.amplitude},
            {"large_step", o.large_step},
            {"step", c.step},
            {"tolerance", c.tolerance},
            {"relative_floor", c.relative_floor},
            {"absolute_floor", c.absolute_floor},
            {"value_tolerance", c.value_tolerance}}},
          {"points", points},
          {"summary", summary}};
}

}  // namespace

int command_gradcheck(const std::string& env_name, const GradientSurveyOptions& options, bool json) {
  const auto env = make_env(env_name);
  if (!env->differentiable()) throw UsageError("env '" + env_name + "' is not differentiable");
  options.validate();
  const auto survey = survey_gradient(*env, options);
  if (json)
    std::cout << to_json(env_name, env->dim(), options, survey).dump() << "\n";
  else
    print_table(env_name, env->dim(), options, survey);
  return survey.passed ? 0 : 1;
}

Command gradcheck_command() {
  return {"gradcheck", "analytic gradient vs central differences, with statistics", [](CLI::App& app) {
            struct Args {
              std::string env;
              GradientSurveyOptions survey;
              bool json = false;
            };
            auto a = std::make_shared<Args>();
            app.add_option("--env", a->env, "env name")->required();
            app.add_option("--points", a->survey.points, "number of seeded random points (default 3)");
            app.add_option("--seed", a->survey.seed, "seed of the points (default 0)");
            app.add_option("--amplitude", a->survey.amplitude, "points uniform in [-a, a]^d (default 0.5)");
            app.add_option("--step", a->survey.check.step, "central-difference step (default 1e-6)");
            app.add_option("--tol", a->survey.check.tolerance, "largest accepted relative error (default 1e-4)");
            app.add_option("--large-step", a->survey.large_step,
                           "step along the gradient of the large-step direction check (default 0.05, 0 = off)");
            app.add_flag("--json", a->json, "one JSON object (per-point worst errors and the summary)");
            return [a] { return command_gradcheck(a->env, a->survey, a->json); };
          }};
}

}  // namespace dsb
