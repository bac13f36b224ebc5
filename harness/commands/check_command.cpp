// `harness check`: the regression gate, a database's result table against a baseline CSV.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "common/error.hpp"
#include "harness/commands/command.hpp"
#include "harness/store/export_ioh.hpp"
#include "harness/core/output_path.hpp"
#include "harness/commands/report_command.hpp"
#include "harness/store/result_table.hpp"
#include "harness/core/shell_word.hpp"
#include "harness/store/sqlite_db.hpp"

namespace dsb {
namespace {

int command_check(const std::string& db_path, const std::string& baseline_path) {
  check_database_path("--db", db_path, true);  // the database first: its problems are named first
  std::vector<ResultRow> baseline;
  try {
    baseline = read_result_csv(baseline_path);
  } catch (const BaselineError& e) {
    throw UsageError(std::string("--baseline: ") + e.what());
  }
  const ResultTable current = result_table_of_file(db_path);
  if (const std::string note = stale_note(current, false); !note.empty()) std::cout << "check: " << note << "\n";
  const TableDiff diff = compare_tables(baseline, current.rows);
  print_diff(diff, std::cout);
  if (diff.empty()) {
    std::cout << "check: database '" << db_path << "' equals baseline '" << baseline_path << "'\n";
    return 0;
  }
  // the command that regenerates this baseline: CI's own script for its baseline, else an export
  const bool ci_baseline = std::filesystem::path(baseline_path).filename() == "small-grid.csv";
  const std::string regenerate = ci_baseline
      ? std::string("scripts/regression-grid.sh regenerate")
      : "harness export --db " + shell_word(db_path) + " --out " + shell_word(baseline_path) + " --force";
  print_verdicts(diff, std::cout, regenerate);
  std::cout << "check: database '" << db_path << "' differs from baseline '" << baseline_path
            << "'. A change of results bumps the results version of what changed and regenerates the baseline in "
               "the same commit, saying why (docs/reports.md, \"Regression CI on result tables\").\n";
  return 1;
}

}  // namespace

Command check_command() {
  return {"check", "regression gate: database result table vs a baseline CSV", [](CLI::App& app) {
            auto db = std::make_shared<std::string>();
            auto baseline = std::make_shared<std::string>();
            app.add_option("--db", *db, "results database")->required();
            app.add_option("--baseline", *baseline, "baseline CSV (data/baselines/NAME.csv)")->required();
            return [db, baseline] { return command_check(*db, *baseline); };
          }};
}

}  // namespace dsb
