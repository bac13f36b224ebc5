// `harness export`: the database's result table as a baseline CSV, or its runs in IOHprofiler's format.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <set>
#include <tuple>

#include <CLI/CLI.hpp>

#include "common/error.hpp"
#include "harness/commands/command.hpp"
#include "harness/store/archive_reader.hpp"
#include "harness/store/export_ioh.hpp"
#include "harness/core/output_path.hpp"
#include "harness/commands/report_command.hpp"
#include "harness/store/result_table.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"

namespace dsb {
namespace {

// --out for ioh is a folder that does not exist yet (created) or an empty folder, so an export
// never mixes with other files; with force, another folder (files of the export's names replaced)
int export_ioh(const std::string& db_path, const std::string& out_path, bool force, bool include_stale,
               const std::string& with) {
  if (db_path.empty() && with.empty()) throw UsageError("export --format ioh needs --db, --with or both");
  if (!db_path.empty()) check_database_path("--db", db_path, true);
  check_output_folder("--out", out_path, force, [](const std::string&) { return false; });
  std::error_code ec;
  const std::filesystem::path out(out_path);
  std::vector<IohRun> runs;
  std::int64_t stale_left_out = 0;
  if (!db_path.empty()) {
    try {
      Database db(db_path, Database::Mode::read_only);
      require_harness_tables(db);  // a newer or foreign file: the message every command gives
      runs = read_ioh_runs(db, include_stale, &stale_left_out);
    } catch (const StoreError& e) {
      const std::string why = e.what();  // SQLite's message, without the statement it quotes
      throw UsageError("--db: cannot read '" + db_path + "': " + why.substr(0, why.find(" in: ")));
    }
  }
  std::int64_t archived = 0, repeated = 0;
  if (!with.empty()) {
    // the published archive beside the database's runs; a key both hold is the database's copy
    ArchivedRuns a = read_archive_runs(with, include_stale);
    stale_left_out += a.stale_left_out;
    const auto key = [](const IohRun& r) {
      return r.env + '\n' + r.optimizer + '\n' + std::to_string(r.seed) + '\n' + std::to_string(r.budget) + '\n' +
          r.env_hash + '\n' + r.opt_hash + '\n' + r.version + '\n' + r.results_versions;
    };
    std::set<std::string> mine;
    for (const auto& r : runs) mine.insert(key(r));
    for (auto& r : a.runs) {
      if (mine.count(key(r))) {
        ++repeated;
        continue;
      }
      runs.push_back(std::move(r));
      ++archived;
    }
    std::stable_sort(runs.begin(), runs.end(), [](const IohRun& x, const IohRun& y) {
      return std::tie(x.env, x.optimizer, x.budget, x.opt_hash, x.env_hash, x.seed, x.run_id) <
          std::tie(y.env, y.optimizer, y.budget, y.opt_hash, y.env_hash, y.seed, y.run_id);
    });
  }
  std::filesystem::create_directories(out, ec);
  if (ec || !std::filesystem::is_directory(out))
    throw UsageError("--out: cannot create folder '" + out_path + "'" + (ec ? ": " + ec.message() : ""));
  const IohExportSummary s = write_ioh_export(runs, out);
  std::cerr << "harness: wrote " << s.runs << " runs (" << s.rows << " rows) of " << s.algorithms << " algorithms on "
            << s.functions << " functions to " << out_path << " (IOHprofiler format)";
  if (s.runs_left_out > 0) std::cerr << "; left out " << s.runs_left_out << " runs without a finite loss";
  if (!with.empty())
    std::cerr << "; " << archived << " of them archived (" << with << ")"
              << (repeated > 0 ? ", " + std::to_string(repeated) + " archived runs the database also holds counted once"
                               : "");
  if (stale_left_out > 0)
    std::cerr << "; left out " << stale_left_out
              << " stale runs (made by other results versions; --include-stale exports them)";
  std::cerr << "\n";
  return 0;
}

int command_export(const std::string& db_path, const std::string& out_path, const std::string& format, bool force,
                   bool include_stale, const std::string& with) {
  if (format != "csv" && format != "ioh") throw UsageError("--format must be csv or ioh, got '" + format + "'");
  if (format == "ioh") return export_ioh(db_path, out_path, force, include_stale, with);
  if (!with.empty()) throw UsageError("--with goes with --format ioh (the CSV is a database's result table)");
  if (db_path.empty()) throw UsageError("export needs --db");
  check_output_file("--out", out_path, force);  // before the database is read: a refusal costs nothing
  const ResultTable table = result_table_of_file(db_path, include_stale);
  OutputFile out("--out", out_path, force);
  write_result_csv(table.rows, out.stream(), include_stale);
  out.commit();
  std::cerr << "harness: wrote " << table.rows.size() << " rows to " << out_path << "\n";
  if (const std::string note = stale_note(table, include_stale); !note.empty())
    std::cerr << "harness: " << note << "\n";
  return 0;
}

}  // namespace

Command export_command() {
  return {"export", "write the database's result table as a baseline CSV, or its runs in IOHprofiler's format",
          [](CLI::App& app) {
            struct Args {
              std::string db, out, format = "csv", with;
              bool force = false, include_stale = false;
            };
            auto a = std::make_shared<Args>();
            app.add_option("--db", a->db, "results database (ioh: optional with --with)");
            app.add_option("--with", a->with,
                           "ioh: a folder of the published archive (data/study) whose runs go beside the database's");
            app.add_option("--out", a->out, "CSV file to write (csv), or a new or empty folder (ioh)")->required();
            app.add_option("--format", a->format, "csv (default: the baseline result table) or ioh (IOHanalyzer)");
            app.add_flag("--force", a->force,
                         "write over an existing file, or into a folder with other files (never over a database)");
            app.add_flag("--include-stale", a->include_stale,
                         "also the runs made by other results versions (stale; csv: a last column stale = 1)");
            return [a] { return command_export(a->db, a->out, a->format, a->force, a->include_stale, a->with); };
          }};
}

}  // namespace dsb
