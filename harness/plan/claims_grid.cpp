#include "harness/plan/claims_grid.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

#include "common/error.hpp"
#include "optimizers/registry.hpp"

namespace dsb {
namespace {

// one CSV record from `text` at `pos` (RFC 4180: quoted fields may hold commas, newlines and
// doubled quotes); false at the end of the text
bool next_record(const std::string& text, std::size_t& pos, std::vector<std::string>& fields) {
  fields.clear();
  if (pos >= text.size()) return false;
  std::string field;
  bool quoted = false;
  for (; pos < text.size(); ++pos) {
    const char c = text[pos];
    if (quoted) {
      if (c == '"' && pos + 1 < text.size() && text[pos + 1] == '"') {
        field.push_back('"');
        ++pos;
      } else if (c == '"') {
        quoted = false;
      } else {
        field.push_back(c);
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.push_back(field);
      field.clear();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && pos + 1 < text.size() && text[pos + 1] == '\n') ++pos;
      ++pos;
      break;
    } else {
      field.push_back(c);
    }
  }
  if (quoted) throw UsageError("claims file: a quoted field is not closed");
  fields.push_back(field);
  return true;
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> w;
  for (std::string x; in >> x;) w.push_back(x);
  return w;
}

}  // namespace

std::vector<ClaimsEnv> claims_envs(const std::string& csv_text) {
  std::size_t pos = 0;
  std::vector<std::string> header, row;
  if (!next_record(csv_text, pos, header)) throw UsageError("claims file: empty");
  auto column = [&](const char* name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw UsageError(std::string("claims file: no column '") + name + "'");
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t c_env = column("env"), c_kind = column("kind"), c_a = column("a"), c_b = column("b");
  std::vector<ClaimsEnv> out;
  std::map<std::string, std::size_t> at;  // env -> index in out
  while (next_record(csv_text, pos, row)) {
    if (row.size() == 1 && row[0].empty()) continue;  // a blank line
    if (row.size() != header.size())
      throw UsageError("claims file: a row has " + std::to_string(row.size()) + " fields, the header " +
                       std::to_string(header.size()));
    if (row[c_kind] == "not_testable") continue;
    std::vector<std::string> opts = words(row[c_a]);
    for (auto& b : words(row[c_b])) opts.push_back(b);
    for (const std::string& env : words(row[c_env])) {
      const auto [it, added] = at.emplace(env, out.size());
      if (added) out.push_back({env, false, {}});
      ClaimsEnv& e = out[it->second];
      e.every_optimizer |= row[c_kind] == "a_best";
      for (const auto& o : opts)
        if (std::find(e.optimizers.begin(), e.optimizers.end(), o) == e.optimizers.end()) e.optimizers.push_back(o);
    }
  }
  return out;
}

std::vector<GridRequest> claims_requests(const GridRequest& base, const std::vector<std::string>& only_envs) {
  const std::vector<ClaimsEnv> envs = claims_envs(paper_claims_csv());
  for (const auto& name : only_envs)
    if (std::none_of(envs.begin(), envs.end(), [&](const ClaimsEnv& e) { return e.env == name; })) {
      std::string known;
      for (const auto& e : envs) known += (known.empty() ? "" : ", ") + e.env;
      throw UsageError("--env " + name + ": no claim of the claims grid is on it (its envs: " + known + ")");
    }
  std::vector<GridRequest> out;
  std::set<std::string> owners_used;
  for (const ClaimsEnv& e : envs) {
    if (!only_envs.empty() && std::find(only_envs.begin(), only_envs.end(), e.env) == only_envs.end()) continue;
    GridRequest r = base;
    r.all = e.every_optimizer;
    r.envs = {e.env};
    r.optimizers = e.every_optimizer ? std::vector<std::string>{} : e.optimizers;
    r.knobs.clear();
    // this request's settings: its env's options and the knobs of its optimizers (an a_best env
    // takes every optimizer, so every knob that names no env)
    for (const auto& [owner, settings] : base.knobs) {
      const bool is_env = std::any_of(envs.begin(), envs.end(), [&](const ClaimsEnv& x) { return x.env == owner; });
      const bool mine = is_env
          ? owner == e.env
          : e.every_optimizer || std::find(e.optimizers.begin(), e.optimizers.end(), owner) != e.optimizers.end();
      if (mine) {
        r.knobs[owner] = settings;
        owners_used.insert(owner);
      }
    }
    out.push_back(std::move(r));
  }
  for (const auto& [owner, settings] : base.knobs) {
    if (owners_used.count(owner)) continue;
    const std::string what = "--set " + owner + "." + settings.begin()->first + ": ";
    const bool claims_env = std::any_of(envs.begin(), envs.end(), [&](const ClaimsEnv& x) { return x.env == owner; });
    const auto& entries = optimizer_entries();
    const bool optimizer =
        std::any_of(entries.begin(), entries.end(), [&](const OptimizerEntry& o) { return o.name == owner; });
    const bool claims_optimizer =
        optimizer && std::any_of(envs.begin(), envs.end(), [&](const ClaimsEnv& x) {
          return x.every_optimizer || std::find(x.optimizers.begin(), x.optimizers.end(), owner) != x.optimizers.end();
        });
    if (claims_env) throw UsageError(what + "env " + owner + " is in the claims grid, but --env leaves it out");
    if (claims_optimizer)
      throw UsageError(what + "optimizer " + owner + " runs on none of the claims grid's envs that --env keeps");
    throw UsageError(what + owner + " is neither an env nor an optimizer of the claims grid");
  }
  return out;
}

}  // namespace dsb
