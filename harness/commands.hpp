#pragma once
// The harness's commands other than `run`: list, eval, gradcheck, landscape, check, export,
// report. Each returns the exit code.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "envs/core/env.hpp"
#include "envs/core/env_options.hpp"
#include "envs/core/gradient_check.hpp"

namespace dsb {

int command_list();
// One rollout of env_name (with its options, --set ENV.KEY=VALUE) at x: JSON on stdout.
int command_eval(const std::string& env_name, const std::string& x_text, bool with_grad,
                 const EnvOptions& options = {});
// Analytic gradient vs central differences at seeded random points (harness/gradcheck_command.cpp):
// a per-point table and the survey's summary, or one JSON object with json. 0 when every point
// passes, 1 when any fails (gradient disagrees, loss() and loss_and_grad() disagree, non-finite).
int command_gradcheck(const std::string& env_name, const GradientSurveyOptions& options, bool json);

// Loss and the two gradient components on an N x N grid over a 2-D slice of the normalized box
// (dims I, J from -1 to 1; other coordinates at the centre, default 0). CSV with header
// i,j,xi,xj,loss,grad_i,grad_j and N^2 rows (gradients empty for a non-differentiable env).
// With `check` (a differentiable env) each point's two components are also checked against
// central differences (check_gradient_along): columns fd_i,fd_j,rel_err,agrees are added (rel_err
// the worse of the two, agrees 1 or 0) and the share of agreeing points is printed, with how often
// the 2-D gradient points within 25 degrees of the differences' direction and how often against it.
// The CSV is written whole or not at all (harness/output_path.hpp), over an existing file only
// with force, never over a database.
int command_landscape(const std::string& env_name, const std::string& dims, int resolution,
                      const std::string& center, const std::string& out_path,
                      const std::optional<GradientCheckOptions>& check = std::nullopt, bool force = false);

// Regression gate: compares the database's result table with a baseline CSV. 0 equal, 1 any
// difference (diff printed), 2 malformed baseline or unreadable database.
int command_check(const std::string& db_path, const std::string& baseline_path);
// Writes the database's result table (the baseline format) to a CSV file (format "csv"), or its
// 'done' runs in IOHprofiler's format to a new or empty folder (format "ioh", export_ioh.hpp).
// Exit 2 for a bad format, an unreadable database or an unusable --out: an existing file without
// force, a database even with force, a folder with other files in it without force.
int command_export(const std::string& db_path, const std::string& out_path, const std::string& format = "csv",
                   bool force = false);
// UsageError unless `dir` may take a report: missing, empty, or a report made before (its
// index.html is ours); any other folder only with force (the option's name in the message)
void check_report_folder(const std::string& dir, bool force, const std::string& option = "--out");
// Runs the Python report generator (reports/make_report.py) with Debian's system interpreter.
// quiet: the generator's stdout is dropped (refreshes during a grid run); gradient_quality: a CSV of
// scripts/gradient-quality.sh for the "Gradient quality" section (empty: the generator's default,
// data/gradient_quality.csv); renders: a folder of scripts/render-best.sh's render_<env>.png
int command_report(const std::string& db_path, const std::string& out_dir, const std::string& landscapes,
                   bool quiet = false, const std::string& gradient_quality = "", const std::string& renders = "");

// Parses a comma-separated list of finite numbers; UsageError naming the bad token.
std::vector<double> parse_number_list(const std::string& option, const std::string& text);
// A point of env's box from text: UsageError for a malformed number, a wrong dimension or a value
// outside [-1, 1], naming the option and the value.
std::vector<double> checked_point(const Env& env, const std::string& x_text, const std::string& option = "--x");

}  // namespace dsb
