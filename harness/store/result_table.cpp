#include "harness/store/result_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>

#include <filesystem>

#include "common/error.hpp"
#include "common/regular_file.hpp"
#include "harness/store/schema.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/stored_runs.hpp"
#include "harness/store/tables.hpp"

namespace dsb {

std::string ResultRow::csv() const {
  std::ostringstream s;
  s << env << ',' << optimizer << ',' << seed << ',' << budget << ',' << env_config_hash << ',' << opt_config_hash
    << ',' << versions.env << ',' << versions.optimizer << ',' << versions.run << ',' << episode << ',' << loss;
  return s.str();
}

std::int64_t ResultTable::stale_runs() const {
  std::int64_t n = 0;
  for (const auto& s : stale) n += s.runs;
  return n;
}

namespace {

std::string format_loss(double v) {
  if (std::isnan(v)) return "nan";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

bool row_less(const ResultRow& a, const ResultRow& b) { return a.key() < b.key(); }

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

template <class T>
bool parse_int(const std::string& s, T& v) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

}  // namespace

ResultTable read_result_table(Database& db, bool include_stale) {
  const int version = check_schema(db);
  const std::string versions = read_column(runs_table(), "results_versions", version);
  ResultTable table;
  // the stale done runs, counted once each, by env, optimizer and reason
  for (const StaleRuns& s : StoredRuns(&db).stale())
    if (s.done > 0) table.stale.push_back({s.env, s.optimizer, s.reason, s.done});
  Statement q(db.handle(),
              "SELECT r.env, r.optimizer, r.seed, r.budget, r.env_config_hash, r.opt_config_hash, " + versions +
                  ", e.episode, e.loss FROM runs r JOIN evals e USING(run_id) "
                  "WHERE r.status = 'done' ORDER BY r.env, r.optimizer, r.seed, r.budget, e.episode");
  std::map<std::pair<std::string, std::string>, bool> stale_of;  // (env, optimizer + versions) -> stale
  while (q.step()) {
    ResultRow row{q.column_text(0),
                  q.column_text(1),
                  static_cast<int>(q.column_int(2)),
                  q.column_int(3),
                  q.column_text(4),
                  q.column_text(5),
                  stored_results_versions(q.column_text(6)),
                  q.column_int(7),
                  format_loss(q.column_double(8))};
    const auto at = std::make_pair(row.env, row.optimizer + "\n" + q.column_text(6));
    auto it = stale_of.find(at);
    if (it == stale_of.end())
      it = stale_of.emplace(at, !stale_reason(row.env, row.optimizer, row.versions).empty()).first;
    row.stale = it->second;
    if (row.stale && !include_stale) continue;
    table.rows.push_back(std::move(row));
  }
  std::stable_sort(table.rows.begin(), table.rows.end(), row_less);
  return table;
}

std::string stale_note(const ResultTable& table, bool included) {
  if (table.stale.empty()) return {};
  std::string text = (included ? "included " : "left out ") + std::to_string(table.stale_runs()) +
      " stale done runs (made by other results versions" +
      (included ? ", marked stale = 1" : "; --include-stale shows them") + "):";
  for (std::size_t i = 0; i < table.stale.size(); ++i) {
    const auto& s = table.stale[i];
    text += (i ? "; " : " ") + s.env + " / " + s.optimizer + ": " + std::to_string(s.runs) + " (" + s.reason + ")";
  }
  return text;
}

std::vector<ResultRow> read_result_csv(const std::string& path) {
  std::istringstream in;
  try {
    in.str(read_regular_file("", path));  // never blocks: a FIFO or device is refused by its kind
  } catch (const UsageError& e) {
    throw BaselineError(std::string("baseline ") + e.what());
  }
  std::string line;
  if (!std::getline(in, line) || line != kResultTableHeader)
    throw BaselineError("baseline '" + path + "' line 1: header must be '" + kResultTableHeader + "'" +
                        (line == "env,optimizer,seed,budget,env_config_hash,opt_config_hash,episode,loss"
                             ? " (this is a table from before results versions: regenerate it)"
                             : ""));
  std::vector<ResultRow> rows;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    const auto f = split(line);
    auto bad = [&](const std::string& why) {
      return BaselineError("baseline '" + path + "' line " + std::to_string(number) + ": " + why);
    };
    if (f.size() != 11) throw bad("expected 11 fields, got " + std::to_string(f.size()));
    ResultRow r;
    r.env = f[0];
    r.optimizer = f[1];
    r.env_config_hash = f[4];
    r.opt_config_hash = f[5];
    r.loss = f[10];
    if (!parse_int(f[2], r.seed)) throw bad("seed '" + f[2] + "' is not an integer");
    if (!parse_int(f[3], r.budget)) throw bad("budget '" + f[3] + "' is not an integer");
    if (!parse_int(f[6], r.versions.env) || r.versions.env < 0)
      throw bad("env_version '" + f[6] + "' is not a whole number");
    if (!parse_int(f[7], r.versions.optimizer) || r.versions.optimizer < 0)
      throw bad("optimizer_version '" + f[7] + "' is not a whole number");
    if (!parse_int(f[8], r.versions.run) || r.versions.run < 0)
      throw bad("run_version '" + f[8] + "' is not a whole number");
    if (!parse_int(f[9], r.episode)) throw bad("episode '" + f[9] + "' is not an integer");
    double v = 0.0;
    const auto [p, ec] = std::from_chars(r.loss.data(), r.loss.data() + r.loss.size(), v);
    if (r.loss != "nan" && (ec != std::errc() || p != r.loss.data() + r.loss.size()))
      throw bad("loss '" + r.loss + "' is not a number");
    rows.push_back(std::move(r));
  }
  std::stable_sort(rows.begin(), rows.end(), row_less);
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (!row_less(rows[i - 1], rows[i])) throw BaselineError("baseline '" + path + "': duplicate row " + rows[i].csv());
  return rows;
}

void write_result_csv(const std::vector<ResultRow>& rows, std::ostream& out, bool with_stale) {
  out << kResultTableHeader << (with_stale ? std::string(",") + kResultTableStaleColumn : std::string()) << '\n';
  for (const auto& r : rows) out << r.csv() << (with_stale ? (r.stale ? ",1" : ",0") : "") << '\n';
}

TableDiff compare_tables(const std::vector<ResultRow>& baseline, const std::vector<ResultRow>& current) {
  TableDiff d;
  std::size_t i = 0, j = 0;
  // both sorted by key: one merge pass
  while (i < baseline.size() || j < current.size()) {
    if (j == current.size() || (i < baseline.size() && row_less(baseline[i], current[j]))) {
      d.missing.push_back(baseline[i++]);
    } else if (i == baseline.size() || row_less(current[j], baseline[i])) {
      d.added.push_back(current[j++]);
    } else {
      const auto& b = baseline[i++];
      const auto& c = current[j++];
      if (b.loss == c.loss && b.env_config_hash == c.env_config_hash && b.opt_config_hash == c.opt_config_hash &&
          b.versions == c.versions)
        ++d.equal;
      else
        d.changed.emplace_back(b, c);
    }
  }
  return d;
}

void print_diff(const TableDiff& d, std::ostream& out, std::size_t limit) {
  out << "check: " << d.equal << " rows equal, " << d.changed.size() << " changed, " << d.missing.size() << " missing, "
      << d.added.size() << " added\n";
  if (!d.changed.empty()) {
    out << "changed (baseline -> now):\n";
    for (std::size_t k = 0; k < std::min(limit, d.changed.size()); ++k) {
      const auto& [b, c] = d.changed[k];
      out << "  " << b.env << " " << b.optimizer << " seed " << b.seed << " budget " << b.budget << " episode "
          << b.episode << ": loss " << b.loss << " -> " << c.loss;
      if (b.env_config_hash != c.env_config_hash)
        out << ", env config " << b.env_config_hash << " -> " << c.env_config_hash;
      if (b.opt_config_hash != c.opt_config_hash)
        out << ", optimizer config " << b.opt_config_hash << " -> " << c.opt_config_hash;
      if (b.versions != c.versions) out << ", results versions " << b.versions.text() << " -> " << c.versions.text();
      out << "\n";
    }
    if (d.changed.size() > limit) out << "  ... and " << d.changed.size() - limit << " more\n";
  }
  auto list = [&](const char* title, const std::vector<ResultRow>& rows) {
    if (rows.empty()) return;
    out << title << "\n";
    for (std::size_t k = 0; k < std::min(limit, rows.size()); ++k) out << "  " << rows[k].csv() << "\n";
    if (rows.size() > limit) out << "  ... and " << rows.size() - limit << " more\n";
  };
  list("missing from the database (in the baseline):", d.missing);
  list("added in the database (not in the baseline):", d.added);
}

ResultTable result_table_of_file(const std::string& db_path, bool include_stale) {
  check_database_path("--db", db_path, true);
  try {
    Database db(db_path, Database::Mode::read_only);
    require_harness_tables(db);  // a newer or foreign file: the message every command gives
    return read_result_table(db, include_stale);
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
}

std::size_t print_verdicts(const TableDiff& d, std::ostream& out, const std::string& regenerate) {
  // per (env, optimizer): rows changed with equal versions (silent), and the versions seen changing
  struct Pair {
    std::int64_t silent = 0, bumped = 0;
    ResultsVersions was, now;
  };
  std::map<std::pair<std::string, std::string>, Pair> pairs;
  for (const auto& [b, c] : d.changed) {
    Pair& p = pairs[{b.env, b.optimizer}];
    if (b.versions == c.versions) {
      ++p.silent;
      p.now = c.versions;
    } else {
      ++p.bumped;
      p.was = b.versions;
      p.now = c.versions;
    }
  }
  std::size_t lines = 0;
  for (const auto& [k, p] : pairs) {
    const auto& [env, optimizer] = k;
    if (p.silent > 0) {
      out << "check: " << env << " / " << optimizer << ": " << p.silent
          << " results changed while its results versions did not (" << p.now.text()
          << "): bump its results version (the env family's in envs/registry.cpp, the optimizer's in "
             "optimizers/registry.cpp, or kRunCodeResultsVersion in harness/core/results_versions.hpp for the run code) "
             "in the commit that changes them, then regenerate the baseline: "
          << regenerate << "\n";
      ++lines;
    } else {
      out << "check: " << env << " / " << optimizer << ": results versions " << p.was.text() << " -> " << p.now.text()
          << " (" << p.bumped << " rows): regenerate the baseline: " << regenerate << "\n";
      ++lines;
    }
  }
  return lines;
}

}  // namespace dsb
