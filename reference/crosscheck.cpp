#include "reference/crosscheck.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "reference/bullet_adapter.hpp"
#include "reference/mujoco_adapter.hpp"

namespace dsb {

bool crosscheck_available() { return reference::mujoco_available() || reference::bullet_available(); }

namespace reference {

namespace {

// compares two rollouts of one vector and folds the worst case into the row
void compare(const Rollout& a, const Rollout& b, const CrosscheckSetup& setup, std::span<const double> x, int index,
             CrosscheckRow& row) {
  const std::size_t n = std::min(a.position.size(), b.position.size());
  double deviation = 0.0;
  for (std::size_t t = 0; t < n; ++t) {
    const double d = (a.position[t] - b.position[t]).norm();
    deviation = std::isfinite(d) ? std::max(deviation, d) : INFINITY;
  }
  const double loss = std::abs(a.final_loss - b.final_loss);
  const double final_position = (a.position[n - 1] - b.position[n - 1]).norm();
  double free_flight = 0.0, rebound = 0.0;
  int impact = 0, bounces = 0;
  if (row.contact) {
    const ContactEvents ea = contact_events(a, setup.gravity(), setup.dt());
    const ContactEvents eb = contact_events(b, setup.gravity(), setup.dt());
    // both engines are in free flight up to the earlier first impact (states 0 .. that step)
    const int free_end = ea.first_impact < 0 ? eb.first_impact
        : eb.first_impact < 0                ? ea.first_impact
                                             : std::min(ea.first_impact, eb.first_impact);
    const std::size_t last = free_end < 0 ? n - 1 : static_cast<std::size_t>(free_end);
    for (std::size_t t = 0; t <= last && t < n; ++t)
      free_flight = std::max(free_flight, (a.position[t] - b.position[t]).norm());
    impact = (ea.first_impact < 0) != (eb.first_impact < 0) ? 1 << 20 : std::abs(ea.first_impact - eb.first_impact);
    bounces = std::abs(setup.floor_bounces(x, a, ea) - setup.floor_bounces(x, b, eb));
    // compared where both have a first impact on a flat surface
    if (ea.first_impact >= 0 && eb.first_impact >= 0) {
      const double d = std::abs(setup.rebound(x, a, ea) - setup.rebound(x, b, eb));
      if (!std::isnan(d)) rebound = d;
    }
  }
  // worst case, and the first quantity (of the first vector) that breaks its tolerance
  auto check = [&](const char* what, double value, double tol) {
    if (tol >= 0.0 && !(value <= tol) && row.pass) {
      row.pass = false;
      char buf[120];
      std::snprintf(buf, sizeof buf, "%s = %.3g > %.3g at vector %d", what, value, tol, index);
      row.failure = buf;
    }
  };
  const Tolerances& tol = row.tol;
  check("deviation", deviation, tol.deviation);
  check("free flight", free_flight, tol.free_flight);
  check("|dloss|", loss, tol.loss);
  check("final position", final_position, tol.final_position);
  check("first impact", impact, tol.first_impact);
  check("rebound", rebound, tol.rebound);
  check("bounces", bounces, tol.bounces);
  row.deviation = std::max(row.deviation, deviation);
  row.free_flight = std::max(row.free_flight, free_flight);
  row.loss = std::isfinite(loss) ? std::max(row.loss, loss) : INFINITY;
  row.final_position = std::max(row.final_position, final_position);
  row.first_impact = std::max(row.first_impact, impact);
  row.rebound = std::max(row.rebound, rebound);
  row.bounces = std::max(row.bounces, bounces);
  ++row.vectors;
}

std::string format_value(double v, double tol) {
  char buf[40];
  if (tol < 0.0)
    std::snprintf(buf, sizeof buf, "%.2e", v);
  else
    std::snprintf(buf, sizeof buf, "%.2e/%g", v, tol);
  return buf;
}

std::string format_count(int v, int tol) {
  char buf[40];
  if (v >= (1 << 20))
    std::snprintf(buf, sizeof buf, "none");
  else if (tol < 0)
    std::snprintf(buf, sizeof buf, "%d", v);
  else
    std::snprintf(buf, sizeof buf, "%d/%d", v, tol);
  return buf;
}

}  // namespace

std::vector<CrosscheckRow> crosscheck(const std::vector<std::string>& envs) {
  const std::vector<std::string>& names = envs.empty() ? crosscheck_envs() : envs;
  for (const auto& name : names) make_setup(name);  // unknown names fail before any work
  std::vector<CrosscheckRow> rows;
  const bool mj = mujoco_available(), bt = bullet_available();
  for (const auto& name : names) {
    const auto owned = make_setup(name);
    CrosscheckSetup& setup = *owned;
    std::vector<std::string> pairs;
    if (mj) pairs.push_back("ours-mujoco");
    if (bt) pairs.push_back("ours-bullet");
    if (mj && bt) pairs.push_back("mujoco-bullet");
    std::vector<CrosscheckRow> env_rows;
    for (const auto& p : pairs) {
      CrosscheckRow row;
      row.env = name;
      row.engines = p;
      row.contact = setup.contact();
      row.tol = setup.tolerances(p);
      env_rows.push_back(row);
    }
    const auto xs = crosscheck_vectors(name);
    for (std::size_t k = 0; k < xs.size(); ++k) {
      const Rollout ours = setup.ours(xs[k]);
      std::optional<Rollout> m, b;
      if (mj) m = setup.mujoco(xs[k]);
      if (bt) b = setup.bullet(xs[k]);
      for (auto& row : env_rows) {
        const int i = static_cast<int>(k);
        if (row.engines == "ours-mujoco") compare(ours, *m, setup, xs[k], i, row);
        if (row.engines == "ours-bullet") compare(ours, *b, setup, xs[k], i, row);
        if (row.engines == "mujoco-bullet") compare(*m, *b, setup, xs[k], i, row);
      }
    }
    rows.insert(rows.end(), env_rows.begin(), env_rows.end());
  }
  return rows;
}

void print_crosscheck(const std::vector<CrosscheckRow>& rows, std::ostream& out) {
  char line[600];
  out << "crosscheck: in-house vs MuJoCo " << mujoco_version() << " vs Bullet " << bullet_version()
      << "\n  worst case over n seeded parameter vectors as value/tolerance (value alone: reported, "
         "not checked; reference/README.md)\n"
      << "  deviation: max |position difference| over the trajectory (m; cartpoles: tip, others: "
         "ball centre)\n"
      << "  free flight: the same up to the first impact; |dloss|: final loss difference; final "
         "pos: final position difference (m)\n"
      << "  impact: first-impact step difference; rebound: first impact's normal restitution "
         "difference (flat faces); bounces: ground/floor bounce-count difference\n";
  const char* fmt = "%-11s %-13s %2s  %-16s %-16s %-16s %-16s %-6s %-14s %-7s %s\n";
  std::snprintf(line, sizeof line, fmt, "env", "engines", "n", "deviation", "free flight", "|dloss|", "final pos",
                "impact", "rebound", "bounces", "result");
  out << line;
  for (const auto& r : rows) {
    const std::string dash = "-";
    const std::string result = r.pass ? "PASS" : "FAIL (" + r.failure + ")";
    std::snprintf(line, sizeof line, fmt, r.env.c_str(), r.engines.c_str(), std::to_string(r.vectors).c_str(),
                  format_value(r.deviation, r.tol.deviation).c_str(),
                  r.contact ? format_value(r.free_flight, r.tol.free_flight).c_str() : dash.c_str(),
                  format_value(r.loss, r.tol.loss).c_str(),
                  format_value(r.final_position, r.tol.final_position).c_str(),
                  r.contact ? format_count(r.first_impact, r.tol.first_impact).c_str() : dash.c_str(),
                  r.contact ? format_value(r.rebound, r.tol.rebound).c_str() : dash.c_str(),
                  r.contact ? format_count(r.bounces, r.tol.bounces).c_str() : dash.c_str(), result.c_str());
    out << line;
  }
}

}  // namespace reference

int run_crosscheck(const std::vector<std::string>& envs, std::ostream& out) {
  if (!crosscheck_available()) {
    out << "crosscheck: this build has neither MuJoCo nor Bullet (DSB_WITH_MUJOCO, DSB_WITH_BULLET)\n";
    return 1;
  }
  const auto rows = reference::crosscheck(envs);
  reference::print_crosscheck(rows, out);
  const bool pass = std::all_of(rows.begin(), rows.end(), [](const auto& r) { return r.pass; });
  out << (pass ? "crosscheck: all tolerances hold\n" : "crosscheck: FAILED\n");
  return pass ? 0 : 1;
}

}  // namespace dsb
