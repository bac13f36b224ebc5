#include "reference/crosscheck.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_env.hpp"
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
    // throws over the whole box; a throw is kept when it is not grazing in our own simulation
    // (every contact episode of ours reverses the ball clearly, none is cut by the horizon)
    const auto& bounce = dynamic_cast<const BounceEnv&>(*env);
    while (xs.size() < 12) {
      std::vector<double> x(3);
      for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
      Rollout r;
      for (const auto& s : bounce.trajectory(x)) {
        r.position.push_back(s.position);
        r.velocity.push_back(s.velocity);
      }
      const ContactEvents e =
          contact_events(r, Eigen::Vector3d(0.0, -bounce.model().gravity, 0.0), bounce.model().dt);
      if (e.episodes == e.bounces) xs.push_back(std::move(x));
    }
  } else {
    // paddle angles over the whole range
    for (int k = 0; k < 8; ++k) {
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
  // episodes: runs of contact steps, gaps of up to kEpisodeGap free steps merged; an episode is a
  // bounce when the velocity change it makes (gravity removed) exceeds kBounceDv
  std::size_t i = 0;
  while (i < contact.size()) {
    std::size_t j = i;
    while (j + 1 < contact.size() && contact[j + 1] - contact[j] <= kEpisodeGap + 1) ++j;
    const int a = contact[i], b = contact[j] + 1;  // states a .. b
    const Eigen::Vector3d dv = r.velocity[b] - r.velocity[a] - (b - a) * dt * gravity;
    ++e.episodes;
    if (dv.norm() > kBounceDv) ++e.bounces;
    i = j + 1;
  }
  return e;
}

Tolerances crosscheck_tolerances(const std::string& env, const std::string& engines) {
  Tolerances t;
  const bool bullet = engines != "ours-mujoco";
  if (env == "cartpole1" || env == "cartpole3") {
    t.deviation = bullet ? 1e-6 : 1e-6;
    t.loss = t.deviation;
    return t;
  }
  t.free_flight = bullet ? 1e-6 : 1e-9;
  t.first_impact = 2;
  if (env == "bounce") {
    t.bounces = 0;
    t.final_position = 0.5;
  }
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
    return tip_rollout("mujoco", impl_->mj_cartpole->tip_trajectory(x), c->cartpole_config());
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
    return tip_rollout("bullet", impl_->bt_cartpole->tip_trajectory(x), c->cartpole_config());
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

// ---------------------------------- table ---------------------------------------------------

namespace {

// compares two rollouts of one vector and folds the worst case into the row
void compare(const Rollout& a, const Rollout& b, const CrosscheckScene& scene, int index,
             CrosscheckRow& row) {
  const std::size_t n = std::min(a.position.size(), b.position.size());
  double deviation = 0.0;
  for (std::size_t t = 0; t < n; ++t) {
    const double d = (a.position[t] - b.position[t]).norm();
    deviation = std::isfinite(d) ? std::max(deviation, d) : INFINITY;
  }
  const double loss = std::abs(a.final_loss - b.final_loss);
  const double final_position = (a.position[n - 1] - b.position[n - 1]).norm();
  double free_flight = 0.0;
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
    bounces = std::abs(ea.bounces - eb.bounces);
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
  check("bounces", bounces, tol.bounces);
  row.deviation = std::max(row.deviation, deviation);
  row.free_flight = std::max(row.free_flight, free_flight);
  row.loss = std::isfinite(loss) ? std::max(row.loss, loss) : INFINITY;
  row.final_position = std::max(row.final_position, final_position);
  row.first_impact = std::max(row.first_impact, impact);
  row.bounces = std::max(row.bounces, bounces);
  ++row.vectors;
}

std::string format_value(double v, double tol) {
  char buf[40];
  if (tol < 0.0) std::snprintf(buf, sizeof buf, "%.2e", v);
  else std::snprintf(buf, sizeof buf, "%.2e/%.0e", v, tol);
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
        if (row.engines == "ours-mujoco") compare(ours, *m, scene, i, row);
        if (row.engines == "ours-bullet") compare(ours, *b, scene, i, row);
        if (row.engines == "mujoco-bullet") compare(*m, *b, scene, i, row);
      }
    }
    rows.insert(rows.end(), env_rows.begin(), env_rows.end());
  }
  return rows;
}

void print_crosscheck(const std::vector<CrosscheckRow>& rows, std::ostream& out) {
  char line[512];
  out << "crosscheck: in-house vs MuJoCo " << mujoco_version() << " vs Bullet " << bullet_version()
      << "\n";
  out << "  value/tolerance; deviation = max |position difference| over the trajectory (m): tip "
         "for cartpoles, ball centre otherwise;\n"
         "  free flight = the same before the first impact; impact = first-impact step "
         "difference; bounces = bounce-count difference\n";
  std::snprintf(line, sizeof line, "%-12s %-14s %3s  %-17s %-17s %-17s %-17s %-7s %-7s %s\n",
                "env", "engines", "n", "deviation", "free flight", "|dloss|", "final position",
                "impact", "bounces", "result");
  out << line;
  for (const auto& r : rows) {
    const std::string dash = "-";
    std::snprintf(line, sizeof line, "%-12s %-14s %3d  %-17s %-17s %-17s %-17s %-7s %-7s %s\n",
                  r.env.c_str(), r.engines.c_str(), r.vectors,
                  format_value(r.deviation, r.tol.deviation).c_str(),
                  r.contact ? format_value(r.free_flight, r.tol.free_flight).c_str() : dash.c_str(),
                  format_value(r.loss, r.tol.loss).c_str(),
                  format_value(r.final_position, r.tol.final_position).c_str(),
                  r.contact ? format_count(r.first_impact, r.tol.first_impact).c_str() : dash.c_str(),
                  r.contact ? format_count(r.bounces, r.tol.bounces).c_str() : dash.c_str(),
                  r.pass ? "PASS" : ("FAIL (" + r.failure + ")").c_str());
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
