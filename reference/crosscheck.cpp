#include "reference/crosscheck.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_env.hpp"
#include "envs/rigid/contact.hpp"
#include "envs/rigid/pinball_env.hpp"
#include "reference/bullet_adapter.hpp"
#include "reference/mujoco_adapter.hpp"

namespace dsb {

bool crosscheck_available() {
  return reference::mujoco_available() || reference::bullet_available();
}

namespace reference {

const std::vector<std::string>& crosscheck_envs() {
  static const std::vector<std::string> names = {"cartpole1", "cartpole3", "bounce", "pinball-1x2",
                                                 "pinball-4x4"};
  return names;
}

namespace {

constexpr std::uint64_t kSeed = 20220711;  // fixed: the table is the same on every run

// the env exactly as the harness builds it (its family's factory)
std::unique_ptr<Env> make_rigid_env(const std::string& name) {
  std::unique_ptr<Env> env;
  if (name == "cartpole1") env = cartpole_family(1).try_make(name);
  if (name == "cartpole3") env = cartpole_family(3).try_make(name);
  if (name == "bounce") env = bounce_family().try_make(name);
  if (name == "pinball-1x2") env = pinball_family(1, 2).try_make(name);
  if (name == "pinball-4x4") env = pinball_family(4, 4).try_make(name);
  if (!env) {
    std::string known;
    for (const auto& n : crosscheck_envs()) known += (known.empty() ? "" : ", ") + n;
    throw UsageError("crosscheck: unknown env '" + name + "' (rigid envs: " + known + ")");
  }
  return env;
}

Eigen::Vector3d lift(const Eigen::Vector2d& p) { return {p.x(), p.y(), 0.0}; }

}  // namespace

std::vector<std::vector<double>> crosscheck_vectors(const std::string& env_name) {
  const auto env = make_rigid_env(env_name);
  Rng rng(kSeed ^ fnv1a64(env_name));
  std::vector<std::vector<double>> xs;
  if (env_name.rfind("cartpole", 0) == 0) {
    // open-loop controls uniform in [-0.5, 0.5] (half the speed and torque bounds)
    for (int k = 0; k < 8; ++k) {
      std::vector<double> x(env->dim());
      for (auto& xi : x) xi = rng.uniform(-0.5, 0.5);
      xs.push_back(std::move(x));
    }
  } else if (env_name == "bounce") {
    // throws over the whole box, kept when they are clear (not grazing, no bounce at the end)
    const auto& cfg = dynamic_cast<const BounceEnv&>(*env).bounce_config();
    while (xs.size() < 24) {
      std::vector<double> x(3);
      for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
      if (bounce_throw_is_clear(cfg, x)) xs.push_back(std::move(x));
    }
  } else {
    // paddle angles over the whole range
    for (int k = 0; k < 12; ++k) {
      std::vector<double> x(env->dim());
      for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
      xs.push_back(std::move(x));
    }
  }
  return xs;
}

ContactEvents contact_events(const Rollout& r, const Eigen::Vector3d& gravity, double dt) {
  ContactEvents e;
  const int steps = static_cast<int>(r.velocity.size()) - 1;
  // contact steps: the velocity change is not gravity's alone
  std::vector<int> contact;
  for (int t = 0; t < steps; ++t)
    if ((r.velocity[t + 1] - r.velocity[t] - dt * gravity).norm() > kContactDv) contact.push_back(t);
  if (contact.empty()) return e;
  e.first_impact = contact.front();
  // episodes: runs of contact steps, gaps of up to kEpisodeGap free steps merged
  std::size_t i = 0;
  while (i < contact.size()) {
    std::size_t j = i;
    while (j + 1 < contact.size() && contact[j + 1] - contact[j] <= kEpisodeGap + 1) ++j;
    const int a = contact[i], b = contact[j] + 1;  // states a .. b
    // the velocity change the contact made (gravity's share removed)
    const Eigen::Vector3d dv = r.velocity[b] - r.velocity[a] - (b - a) * dt * gravity;
    ++e.episodes;
    e.episode_starts.push_back(a);
    e.episode_ends.push_back(b);
    e.episode_bounces.push_back(dv.norm() > kBounceDv);
    e.clearest_graze = std::min(e.clearest_graze, dv.norm());
    if (dv.norm() > kBounceDv) ++e.bounces;
    i = j + 1;
  }
  return e;
}

bool bounce_throw_is_clear(const BounceConfig& cfg, std::span<const double> x) {
  // our own rollout, a quarter longer than the episode
  BounceConfig longer = cfg;
  longer.duration = 1.25 * cfg.duration;
  const BounceEnv env(longer);
  Rollout r;
  for (const auto& s : env.trajectory(x)) {
    r.position.push_back(s.position);
    r.velocity.push_back(s.velocity);
  }
  const ContactEvents e =
      contact_events(r, Eigen::Vector3d(0.0, -env.model().gravity, 0.0), env.model().dt);
  const int horizon = BounceModel::build(cfg).steps;
  if (e.clearest_graze < 2.0) return false;
  for (int start : e.episode_starts) {
    if (start >= static_cast<int>(0.85 * horizon)) return false;
    // one surface at a time: the other one at least 0.3 m beyond the contact radius (a bounce
    // into the corner is one episode in a soft model and two in an impulse one)
    const Eigen::Vector3d& p = r.position[start];
    if (std::max(p.y(), cfg.wall_x - p.x()) < cfg.radius + 0.3) return false;
  }
  return true;
}

Tolerances crosscheck_tolerances(const std::string& env, const std::string& engines) {
  // the figures behind every number are in reference/README.md ("Tolerances")
  Tolerances t;
  const bool ours_bullet = engines == "ours-bullet";
  if (env == "cartpole1" || env == "cartpole3") {
    // contact-free: the same semi-implicit recursion everywhere. 1e-6 is the requirement for
    // MuJoCo; Bullet, measured at 1.1e-13, gets 1e-9 (round-off growth on other builds)
    t.deviation = ours_bullet ? 1e-9 : 1e-6;
    t.loss = t.deviation;
    return t;
  }
  // contact scenes: free flight is the same recursion (measured: bit-identical), contact starts
  // at the same penetration test (measured: the same step); a step of slack for a touch decided
  // by round-off
  t.free_flight = 1e-9;
  t.first_impact = 1;
  // first rebound on a flat face: measured within 0.021 over 374 clear throws and 600 pinball
  // angle vectors
  t.rebound = 0.03;
  if (env == "bounce") {
    // ground bounces: equal on every clear throw (374 of 374, all pairs)
    t.bounces = 0;
    // Bullet's friction is Coulomb's, like ours: final positions measured within 0.39 m; MuJoCo
    // 2.2's soft friction is weaker in impacts, so its final position is reported only
    if (ours_bullet) t.final_position = 0.75;
  }
  // pinball: after a few paddle hits the paths are chaotic, final positions and bounce counts
  // are reported only
  return t;
}

// ---------------------------------- scenes --------------------------------------------------

struct CrosscheckScene::Impl {
  std::unique_ptr<Env> env;
  const CartpoleEnv* cartpole = nullptr;
  const BounceEnv* bounce = nullptr;
  const PinballEnv* pinball = nullptr;
  // engine models built once per env (the pinball's are built per parameter vector)
  std::optional<MujocoCartpole> mj_cartpole;
  std::optional<MujocoBounce> mj_bounce;
  std::unique_ptr<BulletCartpole> bt_cartpole;
  std::unique_ptr<BulletBounce> bt_bounce;
};

CrosscheckScene::CrosscheckScene(const std::string& env) : env_(env), impl_(std::make_unique<Impl>()) {
  impl_->env = make_rigid_env(env);
  impl_->cartpole = dynamic_cast<const CartpoleEnv*>(impl_->env.get());
  impl_->bounce = dynamic_cast<const BounceEnv*>(impl_->env.get());
  impl_->pinball = dynamic_cast<const PinballEnv*>(impl_->env.get());
}

CrosscheckScene::~CrosscheckScene() = default;

int CrosscheckScene::dim() const { return impl_->env->dim(); }
bool CrosscheckScene::contact() const { return impl_->cartpole == nullptr; }

Eigen::Vector3d CrosscheckScene::gravity() const {
  if (impl_->cartpole) return {0.0, -impl_->cartpole->model().gravity, 0.0};
  if (impl_->bounce) return {0.0, -impl_->bounce->model().gravity, 0.0};
  return {0.0, -impl_->pinball->model().gravity, 0.0};
}

double CrosscheckScene::dt() const {
  if (impl_->cartpole) return impl_->cartpole->model().dt;
  if (impl_->bounce) return impl_->bounce->model().dt;
  return impl_->pinball->model().dt;
}

namespace {

// the cartpole loss of a tip: L2 to the target
double tip_loss(const CartpoleConfig& cfg, const Eigen::Vector3d& tip) {
  if (!tip.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  return std::hypot(tip.x() - cfg.target[0], tip.y() - cfg.target[1]);
}

template <class State>
Rollout ball_rollout(const std::string& engine, const std::vector<State>& states, double loss) {
  Rollout r;
  r.engine = engine;
  for (const auto& s : states) {
    if constexpr (std::is_same_v<State, BallState>) {
      r.position.push_back(s.position);
      r.velocity.push_back(s.velocity);
    } else {
      r.position.push_back(lift(s.position));
      r.velocity.push_back(lift(s.velocity));
    }
  }
  r.final_loss = loss;
  return r;
}

Rollout tip_rollout(const std::string& engine, const std::vector<Eigen::Vector2d>& tips,
                    const CartpoleConfig& cfg) {
  Rollout r;
  r.engine = engine;
  for (const auto& p : tips) r.position.push_back(lift(p));
  r.final_loss = tip_loss(cfg, r.position.back());
  return r;
}

}  // namespace

Rollout CrosscheckScene::ours(std::span<const double> x) const {
  if (const auto* c = impl_->cartpole) {
    Rollout r;
    r.engine = "ours";
    const auto states = c->trajectory(x);
    for (const auto& s : states) r.position.push_back(lift(cartpole_tip(c->model(), s)));
    r.final_loss = c->final_loss(states.back());
    return r;
  }
  if (const auto* b = impl_->bounce) {
    const auto states = b->trajectory(x);
    return ball_rollout("ours", states, b->final_loss(states.back()));
  }
  const auto states = impl_->pinball->trajectory(x);
  return ball_rollout("ours", states, impl_->pinball->final_loss(states.back()));
}

Rollout CrosscheckScene::mujoco(std::span<const double> x) {
  if (const auto* c = impl_->cartpole) {
    if (!impl_->mj_cartpole) impl_->mj_cartpole.emplace(c->cartpole_config());
    return tip_rollout("mujoco", impl_->mj_cartpole->tip_trajectory(*c, x), c->cartpole_config());
  }
  if (const auto* b = impl_->bounce) {
    if (!impl_->mj_bounce) impl_->mj_bounce.emplace(b->bounce_config());
    const auto states = impl_->mj_bounce->trajectory(b->initial_velocity(x));
    return ball_rollout("mujoco", states, b->final_loss(states.back()));
  }
  const auto* p = impl_->pinball;
  const auto angles = p->paddle_angles(x);
  MujocoPinball sim(p->pinball_config(), angles);
  const auto states = sim.trajectory();
  return ball_rollout("mujoco", states, p->final_loss(states.back()));
}

Rollout CrosscheckScene::bullet(std::span<const double> x) {
  if (const auto* c = impl_->cartpole) {
    if (!impl_->bt_cartpole) impl_->bt_cartpole = std::make_unique<BulletCartpole>(c->cartpole_config());
    return tip_rollout("bullet", impl_->bt_cartpole->tip_trajectory(*c, x), c->cartpole_config());
  }
  if (const auto* b = impl_->bounce) {
    if (!impl_->bt_bounce) impl_->bt_bounce = std::make_unique<BulletBounce>(b->bounce_config());
    const auto states = impl_->bt_bounce->trajectory(b->initial_velocity(x));
    return ball_rollout("bullet", states, b->final_loss(states.back()));
  }
  const auto* p = impl_->pinball;
  const auto angles = p->paddle_angles(x);
  BulletPinball sim(p->pinball_config(), angles);
  const auto states = sim.trajectory();
  return ball_rollout("bullet", states, p->final_loss(states.back()));
}

CrosscheckScene::Surface CrosscheckScene::nearest_surface(std::span<const double> x,
                                                          const Eigen::Vector3d& p) const {
  // candidates: the signed distance of the centre to each surface and its outward normal
  double best = INFINITY;
  Surface nearest;
  auto consider = [&](const std::string& name, double distance, const Eigen::Vector3d& n,
                      bool flat = true) {
    if (distance < best) {
      best = distance;
      nearest = {name, n, flat};
    }
  };
  if (const auto* b = impl_->bounce) {
    consider("ground", p.y(), Eigen::Vector3d::UnitY());
    consider("wall", b->model().wall_x - p.x(), -Eigen::Vector3d::UnitX());
  } else if (const auto* pin = impl_->pinball) {
    const PinballModel& m = pin->model();
    const int cols = pin->pinball_config().cols;
    consider("floor", p.y(), Eigen::Vector3d::UnitY());
    consider("left wall", p.x(), Eigen::Vector3d::UnitX());
    consider("right wall", m.width - p.x(), -Eigen::Vector3d::UnitX());
    const auto angles = pin->paddle_angles(x);
    for (int k = 0; k < m.paddles; ++k) {
      const Eigen::Vector2d axis(std::cos(angles[k]), std::sin(angles[k]));
      const auto g = capsule_geometry(p.head<2>(), m.centres[k], axis, m.half_segment, m.paddle_radius);
      // a flat face when the closest point of the segment is inside it, else a rounded end
      const bool face = std::abs((p.head<2>() - m.centres[k]).dot(axis)) < m.half_segment;
      consider("paddle " + std::to_string(k / cols) + "," + std::to_string(k % cols), g.distance,
               lift(g.normal), face);
    }
  }
  return nearest;
}

int CrosscheckScene::floor_bounces(std::span<const double> x, const Rollout& r,
                                   const ContactEvents& e) const {
  int n = 0;
  for (std::size_t i = 0; i < e.episode_starts.size(); ++i) {
    if (!e.episode_bounces[i]) continue;
    const std::string name = nearest_surface(x, r.position[e.episode_starts[i]]).name;
    n += name == "ground" || name == "floor";
  }
  return n;
}

double CrosscheckScene::rebound(std::span<const double> x, const Rollout& r,
                                const ContactEvents& e) const {
  if (e.first_impact < 0) return std::numeric_limits<double>::quiet_NaN();
  const int a = e.episode_starts.front(), b = e.episode_ends.front();
  // the ball must stay on one flat face for the whole episode (a fast glancing hit can slide
  // off the face onto the rounded end while a soft contact lasts)
  const Surface surface = nearest_surface(x, r.position[a]);
  const Surface leaving = nearest_surface(x, r.position[b]);
  if (!surface.flat || !leaving.flat || leaving.name != surface.name)
    return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d& n = surface.normal;
  const Eigen::Vector3d v_in = r.velocity[a];
  const Eigen::Vector3d& v_out = r.velocity[b];
  return -v_out.dot(n) / v_in.dot(n);
}

// ---------------------------------- table ---------------------------------------------------

namespace {

// compares two rollouts of one vector and folds the worst case into the row
void compare(const Rollout& a, const Rollout& b, const CrosscheckScene& scene,
             std::span<const double> x, int index, CrosscheckRow& row) {
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
    const ContactEvents ea = contact_events(a, scene.gravity(), scene.dt());
    const ContactEvents eb = contact_events(b, scene.gravity(), scene.dt());
    // both engines are in free flight up to the earlier first impact (states 0 .. that step)
    const int free_end = ea.first_impact < 0   ? eb.first_impact
                         : eb.first_impact < 0 ? ea.first_impact
                                               : std::min(ea.first_impact, eb.first_impact);
    const std::size_t last = free_end < 0 ? n - 1 : static_cast<std::size_t>(free_end);
    for (std::size_t t = 0; t <= last && t < n; ++t)
      free_flight = std::max(free_flight, (a.position[t] - b.position[t]).norm());
    impact = (ea.first_impact < 0) != (eb.first_impact < 0)
                 ? 1 << 20
                 : std::abs(ea.first_impact - eb.first_impact);
    bounces = std::abs(scene.floor_bounces(x, a, ea) - scene.floor_bounces(x, b, eb));
    // compared where both have a first impact on a flat surface
    if (ea.first_impact >= 0 && eb.first_impact >= 0) {
      const double d = std::abs(scene.rebound(x, a, ea) - scene.rebound(x, b, eb));
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
  if (tol < 0.0) std::snprintf(buf, sizeof buf, "%.2e", v);
  else std::snprintf(buf, sizeof buf, "%.2e/%g", v, tol);
  return buf;
}

std::string format_count(int v, int tol) {
  char buf[40];
  if (v >= (1 << 20)) std::snprintf(buf, sizeof buf, "none");
  else if (tol < 0) std::snprintf(buf, sizeof buf, "%d", v);
  else std::snprintf(buf, sizeof buf, "%d/%d", v, tol);
  return buf;
}

}  // namespace

std::vector<CrosscheckRow> crosscheck(const std::vector<std::string>& envs) {
  const std::vector<std::string>& names = envs.empty() ? crosscheck_envs() : envs;
  for (const auto& name : names) make_rigid_env(name);  // unknown names fail before any work
  std::vector<CrosscheckRow> rows;
  const bool mj = mujoco_available(), bt = bullet_available();
  for (const auto& name : names) {
    CrosscheckScene scene(name);
    std::vector<std::string> pairs;
    if (mj) pairs.push_back("ours-mujoco");
    if (bt) pairs.push_back("ours-bullet");
    if (mj && bt) pairs.push_back("mujoco-bullet");
    std::vector<CrosscheckRow> env_rows;
    for (const auto& p : pairs) {
      CrosscheckRow row;
      row.env = name;
      row.engines = p;
      row.contact = scene.contact();
      row.tol = crosscheck_tolerances(name, p);
      env_rows.push_back(row);
    }
    const auto xs = crosscheck_vectors(name);
    for (std::size_t k = 0; k < xs.size(); ++k) {
      const Rollout ours = scene.ours(xs[k]);
      std::optional<Rollout> m, b;
      if (mj) m = scene.mujoco(xs[k]);
      if (bt) b = scene.bullet(xs[k]);
      for (auto& row : env_rows) {
        const int i = static_cast<int>(k);
        if (row.engines == "ours-mujoco") compare(ours, *m, scene, xs[k], i, row);
        if (row.engines == "ours-bullet") compare(ours, *b, scene, xs[k], i, row);
        if (row.engines == "mujoco-bullet") compare(*m, *b, scene, xs[k], i, row);
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
  std::snprintf(line, sizeof line, fmt, "env", "engines", "n", "deviation", "free flight",
                "|dloss|", "final pos", "impact", "rebound", "bounces", "result");
  out << line;
  for (const auto& r : rows) {
    const std::string dash = "-";
    const std::string result = r.pass ? "PASS" : "FAIL (" + r.failure + ")";
    std::snprintf(line, sizeof line, fmt, r.env.c_str(), r.engines.c_str(),
                  std::to_string(r.vectors).c_str(),
                  format_value(r.deviation, r.tol.deviation).c_str(),
                  r.contact ? format_value(r.free_flight, r.tol.free_flight).c_str() : dash.c_str(),
                  format_value(r.loss, r.tol.loss).c_str(),
                  format_value(r.final_position, r.tol.final_position).c_str(),
                  r.contact ? format_count(r.first_impact, r.tol.first_impact).c_str() : dash.c_str(),
                  r.contact ? format_value(r.rebound, r.tol.rebound).c_str() : dash.c_str(),
                  r.contact ? format_count(r.bounces, r.tol.bounces).c_str() : dash.c_str(),
                  result.c_str());
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
