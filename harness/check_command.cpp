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
#include "harness/command.hpp"
#include "harness/export_ioh.hpp"
#include "harness/output_path.hpp"
#include "harness/report_command.hpp"
#include "harness/result_table.hpp"
#include "harness/sqlite_db.hpp"

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
  const auto current = result_table_of_file(db_path);
  const TableDiff diff = compare_tables(baseline, current);
  print_diff(diff, std::cout);
  if (diff.empty()) {
    std::cout << "check: database '" << db_path << "' equals baseline '" << baseline_path << "'\n";
    return 0;
  }
  std::cout << "check: database '" << db_path << "' differs from baseline '" << baseline_path
            << "'. If the change is intended, regenerate the baseline (docs/reports.md, \"Regression CI on result tables\") and say why in the commit.\n";
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
