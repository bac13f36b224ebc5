#include "harness/store/best_run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <iterator>

#include "common/error.hpp"
#include "harness/core/results_versions.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/tables.hpp"

namespace dsb {

BestRun best_run_of(const std::string& db_path, const std::string& env, const std::string& optimizer) {
  check_database_path("--best-of", db_path, true);
  try {
    Database db(db_path, Database::Mode::read_only);
    const int schema = check_schema(db);
    // the best done run whose results versions are this binary's (a stale one is another code's)
    const std::string versions = read_column(runs_table(), "results_versions", schema);
    Statement q(db.handle(),
                "SELECT optimizer, seed, best_loss, best_x, " + versions +
                    " FROM runs WHERE env=? AND (?='' OR optimizer=?) AND status='done' AND best_loss IS NOT "
                    "NULL AND best_x IS NOT NULL ORDER BY best_loss ASC, run_id ASC");
    q.bind(1, env);
    q.bind(2, optimizer);
    q.bind(3, optimizer);
    bool found = false, stale_only = false;
    while (!found && q.step()) {
      found = stale_reason(env, q.column_text(0), stored_results_versions(q.column_text(4))).empty();
      stale_only = stale_only || !found;
    }
    if (!found)
      throw UsageError(fmt::format("--best-of: '{}' holds no done run of env '{}'{}{}", db_path, env,
                                   optimizer.empty() ? "" : fmt::format(" by optimizer '{}'", optimizer),
                                   stale_only ? " made by this binary's results versions (only stale ones)" : ""));
    BestRun r{q.column_text(0), q.column_int(1), q.column_double(2), ""};
    // best_x is a JSON array of numbers
    const auto x = nlohmann::json::parse(q.column_text(3));
    for (const auto& v : x)
      fmt::format_to(std::back_inserter(r.best_x), "{}{}", r.best_x.empty() ? "" : ",", v.get<double>());
    return r;
  } catch (const UsageError&) {
    throw;
  } catch (const std::exception& e) {
    throw UsageError(fmt::format("--best-of: cannot read '{}': {}", db_path, e.what()));
  }
}

}  // namespace dsb
