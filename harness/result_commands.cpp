// `harness check`, `harness export` (csv; ioh through export_ioh), `harness report`: what is done with a finished database.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "common/error.hpp"
#include "harness/commands.hpp"
#include "harness/export_ioh.hpp"
#include "harness/output_path.hpp"
#include "harness/result_table.hpp"
#include "harness/sqlite_db.hpp"

namespace dsb {
namespace {

std::vector<ResultRow> database_table(const std::string& db_path) {
  if (!std::filesystem::is_regular_file(db_path)) throw UsageError("--db: no database file '" + db_path + "'");
  try {
    Database db(db_path, Database::Mode::read_only);
    return read_result_table(db);
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
}

// --out for ioh is a folder that does not exist yet (created) or an empty folder, so an export
// never mixes with other files; with force, another folder (files of the export's names replaced)
int export_ioh(const std::string& db_path, const std::string& out_path, bool force) {
  if (!std::filesystem::is_regular_file(db_path)) throw UsageError("--db: no database file '" + db_path + "'");
  check_output_folder("--out", out_path, force, [](const std::string&) { return false; });
  std::error_code ec;
  const std::filesystem::path out(out_path);
  std::vector<IohRun> runs;
  try {
    Database db(db_path, Database::Mode::read_only);
    runs = read_ioh_runs(db);
  } catch (const StoreError& e) {
    const std::string why = e.what();  // SQLite's message, without the statement it quotes
    throw UsageError("--db: cannot read '" + db_path + "': " + why.substr(0, why.find(" in: ")));
  }
  std::filesystem::create_directories(out, ec);
  if (ec || !std::filesystem::is_directory(out))
    throw UsageError("--out: cannot create folder '" + out_path + "'" + (ec ? ": " + ec.message() : ""));
  const IohExportSummary s = write_ioh_export(runs, out);
  std::cerr << "harness: wrote " << s.runs << " runs (" << s.rows << " rows) of " << s.algorithms
            << " algorithms on " << s.functions << " functions to " << out_path << " (IOHprofiler format)";
  if (s.runs_left_out > 0) std::cerr << "; left out " << s.runs_left_out << " runs without a finite loss";
  std::cerr << "\n";
  return 0;
}

}  // namespace

int command_check(const std::string& db_path, const std::string& baseline_path) {
  std::vector<ResultRow> baseline;
  try {
    baseline = read_result_csv(baseline_path);
  } catch (const BaselineError& e) {
    throw UsageError(std::string("--baseline: ") + e.what());
  }
  const auto current = database_table(db_path);
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

int command_export(const std::string& db_path, const std::string& out_path, const std::string& format,
                   bool force) {
  if (format != "csv" && format != "ioh") throw UsageError("--format must be csv or ioh, got '" + format + "'");
  if (format == "ioh") return export_ioh(db_path, out_path, force);
  check_output_file("--out", out_path, force);  // before the database is read: a refusal costs nothing
  const auto rows = database_table(db_path);
  OutputFile out("--out", out_path, force);
  write_result_csv(rows, out.stream());
  out.commit();
  std::cerr << "harness: wrote " << rows.size() << " rows to " << out_path << "\n";
  return 0;
}

void check_report_folder(const std::string& dir, bool force, const std::string& option) {
  // ours: its index.html is a report's (reports/dsb_report/html.py writes this title)
  const auto is_report = [](const std::string& d) {
    std::ifstream index(std::filesystem::path(d) / "index.html");
    std::string head(4096, '\0');
    index.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(index.gcount()));
    return head.find("<title>diffsim-bench report</title>") != std::string::npos;
  };
  check_output_folder(option, dir, force, is_report, option == "--out" ? "--force" : "");
}

int command_report(const std::string& db_path, const std::string& out_dir, const std::string& landscapes,
                   bool quiet, const std::string& gradient_quality, const std::string& renders) {
  if (!std::filesystem::is_regular_file(db_path)) throw UsageError("--db: no database file '" + db_path + "'");
  // Debian's pandas/matplotlib/scipy import only in Debian's interpreter; DSB_PYTHON overrides
  const char* python_env = std::getenv("DSB_PYTHON");
  const std::string python = python_env ? python_env
                             : std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const char* reports_env = std::getenv("DSB_REPORTS_DIR");
  const std::string script = std::string(reports_env ? reports_env : DSB_SOURCE_DIR "/reports") + "/make_report.py";
  if (!std::filesystem::is_regular_file(script)) throw UsageError("report generator not found at '" + script + "'");
  std::vector<std::string> args = {python, script, "--db", db_path, "--out", out_dir, "--build-type", DSB_BUILD_TYPE};
  // this binary's `list` tells the report which envs exist (a missing env from missing runs)
  std::error_code self_error;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", self_error);
  if (!self_error) {
    args.push_back("--harness");
    args.push_back(self.string());
  }
  if (!landscapes.empty()) {
    args.push_back("--landscapes");
    args.push_back(landscapes);
  }
  if (!gradient_quality.empty()) {
    args.push_back("--gradient-quality");
    args.push_back(gradient_quality);
  }
  if (!renders.empty()) {
    args.push_back("--renders");
    args.push_back(renders);
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  const pid_t pid = fork();
  if (pid == 0) {
    if (quiet) {
      const int devnull = open("/dev/null", O_WRONLY);
      if (devnull >= 0) dup2(devnull, STDOUT_FILENO);
    }
    execvp(argv[0], argv.data());
    std::perror(("harness: cannot run " + python).c_str());
    _exit(127);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0) throw std::runtime_error("cannot start the report generator");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

}  // namespace dsb
