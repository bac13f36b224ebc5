#pragma once
// `harness report`, and what `harness run --report` uses of it.
#include <string>

namespace dsb {

// UsageError unless `dir` may take a report: missing, empty, or a report made before (its
// index.html is ours); any other folder only with force (the option's name in the message)
void check_report_folder(const std::string& dir, bool force, const std::string& option = "--out");
// Runs the Python report generator (reports/make_report.py) with Debian's system interpreter.
// quiet: the generator's stdout is dropped and it ignores SIGINT and SIGHUP, so the terminal's stop
// of a grid does not cut a report short (refreshes during a grid run); gradient_quality: a CSV of
// scripts/gradient-quality.sh for the "Gradient quality" section (empty: the generator's default,
// data/gradient_quality.csv); renders: a folder of scripts/render-best.sh's render_<env>.png;
// include_stale: the report shows the runs of other results versions, marked, instead of leaving
// them out (make_report.py --include-stale; docs/database.md "Results versions"); with: a folder
// of the published archive whose runs join the database's, marked archived (make_report.py --with)
int command_report(const std::string& db_path, const std::string& out_dir, const std::string& landscapes,
                   bool quiet = false, const std::string& gradient_quality = "", const std::string& renders = "",
                   bool include_stale = false, const std::string& with = "");
// (the exit code: the generator's, or 128 + the signal that killed it)

}  // namespace dsb
