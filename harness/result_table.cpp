#include "harness/result_table.hpp"

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
#include "harness/schema.hpp"
#include "harness/sqlite_db.hpp"

namespace dsb {

std::string ResultRow::csv() const {
  std::ostringstream s;
  s << env << ',' << optimizer << ',' << seed << ',' << budget << ',' << env_config_hash << ','
    << opt_config_hash << ',' << episode << ',' << loss;
  return s.str();
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

std::vector<ResultRow> read_result_table(Database& db) {
  Statement q(db.handle(), R"sql(
    SELECT r.env, r.optimizer, r.seed, r.budget, r.env_config_hash, r.opt_config_hash, e.episode, e.loss
    FROM runs r JOIN evals e USING(run_id) WHERE r.status = 'done'
    ORDER BY r.env, r.optimizer, r.seed, r.budget, e.episode)sql");
  std::vector<ResultRow> rows;
  while (q.step())
    rows.push_back({q.column_text(0), q.column_text(1), static_cast<int>(q.column_int(2)),
                    q.column_int(3), q.column_text(4), q.column_text(5), q.column_int(6),
                    format_loss(q.column_double(7))});
  std::stable_sort(rows.begin(), rows.end(), row_less);
  return rows;
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
    throw BaselineError("baseline '" + path + "' line 1: header must be '" + kResultTableHeader + "'");
  std::vector<ResultRow> rows;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    const auto f = split(line);
    auto bad = [&](const std::string& why) {
      return BaselineError("baseline '" + path + "' line " + std::to_string(number) + ": " + why);
    };
    if (f.size() != 8) throw bad("expected 8 fields, got " + std::to_string(f.size()));
    ResultRow r;
    r.env = f[0];
    r.optimizer = f[1];
    r.env_config_hash = f[4];
    r.opt_config_hash = f[5];
    r.loss = f[7];
    if (!parse_int(f[2], r.seed)) throw bad("seed '" + f[2] + "' is not an integer");
    if (!parse_int(f[3], r.budget)) throw bad("budget '" + f[3] + "' is not an integer");
    if (!parse_int(f[6], r.episode)) throw bad("episode '" + f[6] + "' is not an integer");
    double v = 0.0;
    const auto [p, ec] = std::from_chars(r.loss.data(), r.loss.data() + r.loss.size(), v);
    if (r.loss != "nan" && (ec != std::errc() || p != r.loss.data() + r.loss.size()))
      throw bad("loss '" + r.loss + "' is not a number");
    rows.push_back(std::move(r));
  }
  std::stable_sort(rows.begin(), rows.end(), row_less);
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (!row_less(rows[i - 1], rows[i]))
      throw BaselineError("baseline '" + path + "': duplicate row " + rows[i].csv());
  return rows;
}

void write_result_csv(const std::vector<ResultRow>& rows, std::ostream& out) {
  out << kResultTableHeader << '\n';
  for (const auto& r : rows) out << r.csv() << '\n';
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
      if (b.loss == c.loss && b.env_config_hash == c.env_config_hash && b.opt_config_hash == c.opt_config_hash)
        ++d.equal;
      else
        d.changed.emplace_back(b, c);
    }
  }
  return d;
}

void print_diff(const TableDiff& d, std::ostream& out, std::size_t limit) {
  out << "check: " << d.equal << " rows equal, " << d.changed.size() << " changed, " << d.missing.size()
      << " missing, " << d.added.size() << " added\n";
  if (!d.changed.empty()) {
    out << "changed (baseline -> now):\n";
    for (std::size_t k = 0; k < std::min(limit, d.changed.size()); ++k) {
      const auto& [b, c] = d.changed[k];
      out << "  " << b.env << " " << b.optimizer << " seed " << b.seed << " budget " << b.budget
          << " episode " << b.episode << ": loss " << b.loss << " -> " << c.loss;
      if (b.env_config_hash != c.env_config_hash) out << ", env config " << b.env_config_hash << " -> " << c.env_config_hash;
      if (b.opt_config_hash != c.opt_config_hash) out << ", optimizer config " << b.opt_config_hash << " -> " << c.opt_config_hash;
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

std::vector<ResultRow> result_table_of_file(const std::string& db_path) {
  check_database_path("--db", db_path, true);
  try {
    Database db(db_path, Database::Mode::read_only);
    require_harness_tables(db);  // a newer or foreign file: the message every command gives
    return read_result_table(db);
  } catch (const StoreError& e) {
    throw UsageError(std::string("--db: ") + e.what());
  }
}

}  // namespace dsb
