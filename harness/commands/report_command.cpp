// `harness report`: the comparison report (index.html, figures, tables) of a database, made by
// reports/make_report.py.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "common/error.hpp"
#include "common/regular_file.hpp"
#include "common/shown_value.hpp"
#include "harness/commands/command.hpp"
#include "harness/store/export_ioh.hpp"
#include "harness/core/output_path.hpp"
#include "harness/commands/report_command.hpp"
#include "harness/store/result_table.hpp"
#include "harness/store/sqlite_db.hpp"

namespace dsb {

void check_report_folder(const std::string& dir, bool force, const std::string& option) {
  // ours: its index.html is a report's (reports/dsb_report/html.py writes this title)
  const auto is_report = [](const std::string& d) {
    std::string head;
    try {
      head = read_regular_file("", (std::filesystem::path(d) / "index.html").string());  // a FIFO never blocks
    } catch (const UsageError&) {
      return false;  // no index.html, or not a regular file: not a report of ours
    }
    return head.find("<title>diffsim-bench report</title>") != std::string::npos;
  };
  check_output_folder(option, dir, force, is_report, option == "--out" ? "--force" : "");
}

int command_report(const std::string& db_path, const std::string& out_dir, const std::string& landscapes, bool quiet,
                   const std::string& gradient_quality, const std::string& renders, bool include_stale,
                   const std::string& with) {
  check_database_path("--db", db_path, true);
  // Debian's pandas/matplotlib/scipy import only in Debian's interpreter; DSB_PYTHON overrides
  const char* python_env = std::getenv("DSB_PYTHON");
  const std::string python = python_env             ? python_env
      : std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3"
                                                    : "python3";
  const char* reports_env = std::getenv("DSB_REPORTS_DIR");
  const std::string script = std::string(reports_env ? reports_env : DSB_SOURCE_DIR "/reports") + "/make_report.py";
  if (!std::filesystem::is_regular_file(script)) throw UsageError("report generator not found at '" + script + "'");
  std::vector<std::string> args = {python, script, "--db", db_path, "--out", out_dir, "--build-type", DSB_BUILD_TYPE};
  // this binary's `list` tells the report which envs exist (a missing env from missing runs) and
  // its results versions, which make a stored run current or stale
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
  if (include_stale) args.push_back("--include-stale");
  if (!with.empty()) {
    if (!std::filesystem::is_directory(with))
      throw UsageError("--with: '" + shown_value(with) + "' is not a folder of archive files (NAME.runs.jsonl.gz)");
    args.push_back("--with");
    args.push_back(with);
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
      // a refresh during a grid finishes what it writes: the Ctrl-C or closed terminal that stops
      // the grid reaches the terminal's whole process group, this child too, and would kill it
      // mid-write (a Python traceback, a half-written report) although the harness stops in order
      // and builds the report once more at the end. Ignored signals stay ignored across exec, and
      // Python then installs no KeyboardInterrupt handler.
      ::signal(SIGINT, SIG_IGN);
      ::signal(SIGHUP, SIG_IGN);
    }
    execvp(argv[0], argv.data());
    std::perror(("harness: cannot run " + python).c_str());
    _exit(127);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0) throw std::runtime_error("cannot start the report generator");
  // the shell's convention: 128 + the signal that killed the generator
  return WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : 1;
}

Command report_command() {
  return {"report", "comparison report (index.html, figures, tables) from a database", [](CLI::App& app) {
            struct Args {
              std::string db = "results.sqlite", out = "report", landscapes, gradient_quality, renders, with;
              bool force = false, include_stale = false;
            };
            auto a = std::make_shared<Args>();
            app.add_option("--db", a->db, "results database (default ./results.sqlite)");
            app.add_option("--out", a->out, "output folder (default ./report)");
            app.add_option("--landscapes", a->landscapes, "folder of `harness landscape` CSVs to plot");
            app.add_option("--gradient-quality", a->gradient_quality,
                           "CSV of scripts/gradient-quality.sh (default data/gradient_quality.csv)");
            app.add_option("--renders", a->renders, "folder of scripts/render-best.sh's render_<env>.png to show");
            app.add_flag("--force", a->force,
                         "write into a folder that holds other files (files of the report's names are replaced)");
            app.add_flag("--include-stale", a->include_stale,
                         "also the runs made by other results versions (stale), each marked as an optimizer of "
                         "its own (OPT-stale-eEoOrR); the claims still judge current runs only");
            app.add_option("--with", a->with,
                           "a folder of the published archive (data/study): its runs beside yours, marked archived "
                           "(docs/results.md)");
            return [a] {
              check_report_folder(a->out, a->force);
              return command_report(a->db, a->out, a->landscapes, false, a->gradient_quality, a->renders,
                                    a->include_stale, a->with);
            };
          }};
}

}  // namespace dsb
