#include "harness/store/run_key_sql.hpp"

#include <stdexcept>
#include <vector>

#include "harness/store/schema.hpp"
#include "harness/store/tables.hpp"

namespace dsb {
namespace {

// runs' UNIQUE key of the newest schema: RunKey's fields, in its order
const std::vector<std::string>& key_names() {
  static const std::vector<std::string> names = [] {
    auto n = unique_key_columns(runs_table(), kSchemaVersion);
    const std::vector<std::string> run_key = {"env",
                                              "optimizer",
                                              "seed",
                                              "budget",
                                              "env_config_hash",
                                              "opt_config_hash",
                                              "harness_version",
                                              "results_versions"};
    if (n != run_key) throw std::logic_error("runs' UNIQUE key is not RunKey's fields");
    return n;
  }();
  return names;
}

}  // namespace

std::string run_key_columns(int version) {
  std::string sql;
  for (const auto& c : key_names()) sql += (sql.empty() ? "" : ", ") + read_column(runs_table(), c, version);
  return sql;
}

RunKey read_run_key(const Statement& q, int first) {
  return {q.column_text(first),
          q.column_text(first + 1),
          static_cast<int>(q.column_int(first + 2)),
          q.column_int(first + 3),
          q.column_text(first + 4),
          q.column_text(first + 5),
          q.column_text(first + 6),
          stored_results_versions(q.column_text(first + 7))};
}

std::string run_key_match(bool with_seed) {
  std::string sql;
  for (const auto& c : key_names())
    if (with_seed || c != "seed") sql += (sql.empty() ? "" : " AND ") + c + "=?";
  return sql;
}

void bind_run_key(Statement& st, int first, const RunKey& key, bool with_seed) {
  int i = first;
  st.bind(i++, key.env);
  st.bind(i++, key.optimizer);
  if (with_seed) st.bind(i++, static_cast<std::int64_t>(key.seed));
  st.bind(i++, key.budget);
  st.bind(i++, key.env_config_hash);
  st.bind(i++, key.opt_config_hash);
  st.bind(i++, key.harness_version);
  st.bind(i++, key.versions.text());
}

}  // namespace dsb
