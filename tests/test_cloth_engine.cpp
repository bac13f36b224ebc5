// The mass-spring cloth engine (envs/cloth/): closed-form and single-effect checks of the forward
// step (a spring-mass oscillator's period, a hanging cloth's static equilibrium, bounded energy
// without damping, floor contact that never lets a vertex move further in), the hand-written
// reverse pass against central differences of the forward pass (initial state, log-stiffness,
// spring damping, anchor path, the parameters of a moving curved surface; with and without
// contact in the episode) and bit-identical reruns.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/det_math.hpp"
#include "common/rng.hpp"
#include "envs/cloth/cloth_dynamics.hpp"
#include "envs/cloth/cloth_model.hpp"

namespace dsb::cloth {
namespace {

std::vector<Vec3> constant_path(const ClothModel& m, int steps) {
  return anchor_path_from(m, steps, [&](int a, double) -> Vec3 { return m.rest_position[m.anchors[a].vertex]; });
}

// ---------------------------------------------------------------------------------------------
// forward physics

TEST(ClothPhysics, SpringMassOscillatorHasThePeriodTwoPiSqrtMOverK) {
  // vertex 0 held at the origin, vertex 1 on a spring of k = 20 N/m with m = 0.05 kg, pulled
  // 1 cm past its rest length 0.1 m; no gravity, no damping: T = 2 pi sqrt(m / k) = 0.3142 s.
  // Symplectic Euler at omega dt = 0.02 has the period 2 pi / theta with cos theta = 1 -
  // (omega dt)^2 / 2, i.e. a relative error of about (omega dt)^2 / 24 = 1.7e-5.
  ClothModel m;
  const double k = 20.0, mass = 0.05, L0 = 0.1;
  m.rest_position = {Vec3::Zero(), Vec3(L0 + 0.01, 0.0, 0.0)};
  m.mass = {1.0, mass};
  m.springs = {{0, 1, L0, k, 0.0, SpringKind::other}};
  m.anchors = {{0}};
  m.gravity = Vec3::Zero();
  m.dt = 1e-3;
  m.validate();
  const int steps = 4000;
  const auto path = constant_path(m, steps);
  const auto stiffness = m.default_stiffness();
  const ClothInputs in{stiffness, path};
  ClothState s = rest_state(m);
  std::vector<Vec3> force(2);
  std::vector<double> crossings;  // upward zero crossings of the stretch, linearly interpolated
  double before = s.x[1].x() - L0;
  for (int t = 0; t < steps; ++t) {
    cloth_step(m, in, t, s, force);
    const double after = s.x[1].x() - L0;
    if (before < 0.0 && after >= 0.0) crossings.push_back((t + before / (before - after)) * m.dt);
    before = after;
  }
  ASSERT_GE(crossings.size(), 11u);
  const double measured = (crossings[10] - crossings[0]) / 10.0;
  const double expected = 2.0 * std::numbers::pi * std::sqrt(mass / k);
  const double rel = std::abs(measured - expected) / expected;
  std::printf("[cloth] oscillator: period %.6f s, expected %.6f s, relative error %.2e\n", measured, expected, rel);
  EXPECT_LT(rel, 0.01);             // the requirement
  EXPECT_LT(rel, 1e-3);             // what the integrator's (omega dt)^2 / 24 promises, with margin
  EXPECT_EQ(s.x[0], Vec3::Zero());  // the anchor never moved
}

GridSpec test_cloth(int n) {
  GridSpec g;
  g.cols = g.rows = n;
  g.width = g.height = 0.2;
  g.total_mass = 0.1;
  g.structural_stiffness = 100.0;
  g.shear_stiffness = 50.0;
  g.bending_stiffness = 20.0;
  return g;
}

TEST(ClothPhysics, HangingClothConvergesToAStaticSag) {
  // 9 x 9 vertices, 20 x 20 cm, 0.1 kg, hanging in the x-y plane from its two top corners;
  // dashpots 0.05 N s/m on every spring and global damping 3 / s
  GridSpec g = test_cloth(9);
  g.origin = Vec3(0.0, 0.5, 0.0);
  g.axis_v = -Vec3::UnitY();  // row 0 on top
  g.structural_damping = g.shear_damping = g.bending_damping = 0.05;
  ClothModel m = build_grid(g);
  m.anchors = {{0}, {8}};
  m.damping = 3.0;
  const auto stiffness = m.default_stiffness();
  // dt 1e-4: omega_max dt <= 0.11 (stable below 2)
  m.dt = 1e-4;
  ASSERT_LT(frequency_bound(m, stiffness) * m.dt, 0.2);
  const int steps = 60000;  // 6 s: the slowest (pendulum) modes decay like exp(-3 t)
  const auto path = constant_path(m, steps);
  const ClothInputs in{stiffness, path};
  ClothState s = rest_state(m);
  std::vector<Vec3> force(m.vertices());
  for (int t = 0; t < steps; ++t) cloth_step(m, in, t, s, force);
  double vmax = 0.0;
  for (const Vec3& v : s.v) vmax = std::max(vmax, v.norm());
  // residual force on every free vertex against its weight (static equilibrium)
  cloth_forces(m, stiffness, s, force);
  double residual = 0.0;
  for (int i = 0; i < m.vertices(); ++i)
    if (i != 0 && i != 8) residual = std::max(residual, force[i].norm() / (m.mass[i] * 9.81));
  // the anchors carry the whole weight, half each by symmetry: the spring forces cancel in
  // pairs, so -(f_0 + f_8) = M g + sum over free vertices of f_y, = M g at equilibrium
  const double weight = 0.1 * 9.81;
  const double carried = -(force[0].y() + force[8].y());
  const double sag = 0.5 - s.x[4].y();    // top-middle vertex below the corners
  const double drop = 0.3 - s.x[76].y();  // bottom-middle vertex below its rest height 0.3 m
  std::printf(
      "[cloth] hanging: max |v| %.2e m/s, residual %.2e of a vertex weight, anchors carry %.6f N "
      "(weight %.6f N, left %.6f right %.6f), top sag %.5f m, bottom drop %.5f m\n",
      vmax, residual, carried, weight, -force[0].y(), -force[8].y(), sag, drop);
  EXPECT_LT(vmax, 1e-5);
  EXPECT_LT(residual, 1e-4);
  EXPECT_NEAR(carried, weight, 1e-4 * weight);
  EXPECT_NEAR(force[0].y(), force[8].y(), 1e-6 * weight);
  // plausibility: the cloth sags and stretches downward, by less than a tenth of its size
  EXPECT_GT(sag, 1e-4);
  EXPECT_LT(sag, 0.02);
  EXPECT_GT(drop, 0.0);
  EXPECT_LT(drop, 0.05);
}

// Max |E(t) - E(0)| of the free swing (see below) over [0, T/2] and [T/2, T], and the largest
// kinetic energy, at time step dt.
struct EnergyRun {
  double first_half = 0.0, second_half = 0.0, max_kinetic = 0.0, omega_dt = 0.0;
  double max_dev() const { return std::max(first_half, second_half); }
};

EnergyRun free_swing(double dt, double seconds) {
  GridSpec g = test_cloth(9);
  g.origin = Vec3(0.0, 0.5, 0.0);
  ClothModel m = build_grid(g);
  m.anchors = {{0}, {8}};
  m.dt = dt;
  const auto stiffness = m.default_stiffness();
  const int steps = static_cast<int>(std::lround(seconds / dt));
  const auto path = constant_path(m, steps);
  const ClothInputs in{stiffness, path};
  ClothState s = rest_state(m);
  std::vector<Vec3> force(m.vertices());
  const double e0 = cloth_energy(m, stiffness, s).total();
  EnergyRun r;
  r.omega_dt = frequency_bound(m, stiffness) * dt;
  for (int t = 0; t < steps; ++t) {
    cloth_step(m, in, t, s, force);
    const ClothEnergy e = cloth_energy(m, stiffness, s);
    double& half = 2 * t < steps ? r.first_half : r.second_half;
    half = std::max(half, std::abs(e.total() - e0));
    r.max_kinetic = std::max(r.max_kinetic, e.kinetic);
  }
  return r;
}

TEST(ClothPhysics, EnergyStaysBoundedWithoutDampingOrContact) {
  // the 9 x 9 cloth held flat by two corners and released: it falls and swings for 10 s with no
  // damping at all. Symplectic Euler conserves a modified energy H + O(dt): the true energy
  // oscillates without drift, with an amplitude of about omega dt / 2 of the energy exchanged at
  // frequency omega (for a linear oscillator the conserved quantity is H - dt/2 k q p / m, and
  // k |q p| / m <= omega H). Bounds: omega_max dt / 2 of the largest kinetic energy, with
  // omega_max from the Gershgorin bound; no secular growth (the second half's largest deviation
  // within twice the first half's); first order in dt (doubling dt roughly doubles it).
  const EnergyRun a = free_swing(1e-4, 10.0);
  const EnergyRun b = free_swing(2e-4, 10.0);
  for (const EnergyRun* r : {&a, &b})
    std::printf(
        "[cloth] energy (omega_max dt %.3f): max |E - E0| %.3e J in [0, 5] s, %.3e J in [5, 10] s, "
        "largest kinetic %.4e J, relative %.3e (bound omega_max dt / 2 = %.3e)\n",
        r->omega_dt, r->first_half, r->second_half, r->max_kinetic, r->max_dev() / r->max_kinetic, r->omega_dt / 2.0);
  std::printf("[cloth] energy: deviation ratio for 2 dt / dt = %.3f\n", b.max_dev() / a.max_dev());
  for (const EnergyRun* r : {&a, &b}) {
    ASSERT_GT(r->max_kinetic, 0.05 * 0.1 * 9.81);  // it really fell (at least 5 cm of its weight)
    EXPECT_LT(r->max_dev() / r->max_kinetic, r->omega_dt / 2.0);
    EXPECT_LT(r->second_half, 2.0 * r->first_half);
    EXPECT_GT(r->first_half, 0.0);  // not vacuous: the integrator is not exact
  }
  EXPECT_GT(b.max_dev() / a.max_dev(), 1.3);
  EXPECT_LT(b.max_dev() / a.max_dev(), 3.0);
}

TEST(ClothPhysics, FloorContactNeverLetsAVertexMoveFurtherIn) {
  // a 9 x 9 cloth dropped flat from 5 cm with a random tumble onto the floor y = 0, for both
  // the frictionless projection and half the tangential velocity kept
  for (const double keep : {1.0, 0.5}) {
    GridSpec g = test_cloth(9);
    g.origin = Vec3(0.0, 0.05, 0.0);
    g.structural_damping = g.shear_damping = g.bending_damping = 0.02;
    ClothModel m = build_grid(g);
    m.surfaces = {PlaneSurface::floor()};
    m.damping = 1.0;
    m.tangential_keep = keep;
    m.dt = 1e-4;
    const auto stiffness = m.default_stiffness();
    const ClothInputs in{stiffness, {}};
    ClothState s = rest_state(m);
    Rng rng(7);
    for (Vec3& v : s.v) v = Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-1.0, 0.0), rng.uniform(-0.3, 0.3));
    std::vector<Vec3> force(m.vertices());
    int contacts = 0, violations = 0;
    double deepest = 0.0, tol_used = 0.0;
    for (int t = 0; t < 8000; ++t) {
      const std::vector<Vec3> x_start = s.x;
      cloth_step(m, in, t, s, force);
      double vmax = 0.0;
      for (const Vec3& v : s.v) vmax = std::max(vmax, v.norm());
      // a vertex enters at most one step's travel and then never moves further in, so the
      // depth is bounded by the largest dt |v| seen so far
      tol_used = std::max(tol_used, m.dt * vmax);
      const double tol = tol_used;
      for (int i = 0; i < m.vertices(); ++i) {
        // a vertex that started the step on or in the floor leaves it not moving further in
        if (x_start[i].y() <= 0.0) {
          ++contacts;
          if (s.v[i].y() < 0.0) ++violations;
        }
        // no vertex below -tol, and none below the floor moving further in unless it just arrived
        if (s.x[i].y() < -tol) ++violations;
        if (s.x[i].y() < 0.0 && s.v[i].y() < 0.0 && x_start[i].y() <= 0.0) ++violations;
        deepest = std::max(deepest, -s.x[i].y());
      }
    }
    std::printf(
        "[cloth] floor (tangential_keep %.1f): %d vertex-steps in contact, deepest %.2e m "
        "(one step's travel <= %.2e m), violations %d\n",
        keep, contacts, deepest, tol_used, violations);
    EXPECT_GT(contacts, 1000);  // it landed
    EXPECT_EQ(violations, 0);
    EXPECT_LT(deepest, 2e-4);  // entering at <= ~1.2 m/s for one step of 1e-4 s
  }
}

// ---------------------------------------------------------------------------------------------
// reverse pass vs central differences

// A test surface with parameters, to exercise every term of the contact reverse: a ball of
// radius R (curved: dn/dx != 0) whose centre c, translation velocity U and spin omega are the 9
// parameters; surface velocity u = U + omega x (x - c) (du/dx = [omega]_x).
class Ball final : public ContactSurface {
 public:
  Ball(const std::array<double, 9>& p, double radius) : p_(p), r_(radius) {}
  Vec3 c() const { return Vec3(p_[0], p_[1], p_[2]); }
  Vec3 U() const { return Vec3(p_[3], p_[4], p_[5]); }
  Vec3 w() const { return Vec3(p_[6], p_[7], p_[8]); }
  static Mat3 cross(const Vec3& a) {
    Mat3 m;
    m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    return m;
  }
  SurfaceSample sample(int, const Vec3& x) const override {
    SurfaceSample s;
    const Vec3 d = x - c();
    const double len = d.norm();
    s.distance = len - r_;
    s.normal = d / len;
    s.dnormal_dx = (Mat3::Identity() - s.normal * s.normal.transpose()) / len;
    s.velocity = U() + w().cross(d);
    s.dvelocity_dx = cross(w());
    return s;
  }
  int param_count() const override { return 9; }
  void sample_adjoint(int, const Vec3& x, const Vec3& n_bar, const Vec3& u_bar, std::span<double> g) const override {
    const Vec3 d = x - c();
    const double len = d.norm();
    const Vec3 n = d / len;
    const Mat3 J = (Mat3::Identity() - n * n.transpose()) / len;
    // dn/dc = -J; du/dc = -[w]_x; du/dU = I; du/dw = -[d]_x
    const Vec3 gc = -J.transpose() * n_bar - cross(w()).transpose() * u_bar;
    const Vec3 gw = -cross(d).transpose() * u_bar;
    for (int k = 0; k < 3; ++k) {
      g[k] += gc[k];
      g[3 + k] += u_bar[k];
      g[6 + k] += gw[k];
    }
  }
  std::array<double, 9> p_;
  double r_;
};

// One gradient problem: the loss is |x_T - target|^2 summed over vertices plus per-step terms
// dt sum_t (w_x |x_t - target|^2 + w_v |v_t|^2) (exercise the per-step adjoint input, the
// pinned x_0 of held anchors included).
struct Problem {
  ClothModel model;
  std::vector<double> log_k;  // (n_springs)
  std::vector<Vec3> path;
  ClothState s0;
  int steps = 0;
  std::vector<Vec3> target;
  double w_v = 0.05, w_x = 0.5;
  int ball = -1;  // index of a Ball among the surfaces, or -1
};

double loss_of(const Problem& p, ClothTape& tape) {
  std::vector<double> k(p.log_k.size());
  for (std::size_t s = 0; s < k.size(); ++s) k[s] = dm::exp(p.log_k[s]);
  const ClothState f = cloth_rollout(p.model, {k, p.path}, p.s0, p.steps, tape);
  double L = 0.0;
  for (int i = 0; i < p.model.vertices(); ++i) L += (f.x[i] - p.target[i]).squaredNorm();
  for (int t = 0; t <= p.steps; ++t)
    for (int i = 0; i < p.model.vertices(); ++i)
      L += p.model.dt * (p.w_x * (tape.x(t)[i] - p.target[i]).squaredNorm() + p.w_v * tape.v(t)[i].squaredNorm());
  return L;
}

double loss_and_gradient(const Problem& p, ClothTape& tape, ClothGradient& grad) {
  const double L = loss_of(p, tape);
  std::vector<double> k(p.log_k.size());
  for (std::size_t s = 0; s < k.size(); ++s) k[s] = dm::exp(p.log_k[s]);
  ClothAdjoint fb;
  fb.reset(p.model.vertices());
  for (int i = 0; i < p.model.vertices(); ++i) fb.x[i] = 2.0 * (tape.x(p.steps)[i] - p.target[i]);
  const double wv = p.w_v * p.model.dt, wx = p.w_x * p.model.dt;
  cloth_rollout_adjoint(
      p.model, {k, p.path}, tape, fb,
      [&](int, std::span<const Vec3> x, std::span<const Vec3> v, ClothAdjoint& adj) {
        for (std::size_t i = 0; i < v.size(); ++i) {
          adj.x[i] += 2.0 * wx * (x[i] - p.target[i]);
          adj.v[i] += 2.0 * wv * v[i];
        }
      },
      grad);
  // chain rule to log-stiffness: dL/dlog k = k dL/dk
  for (std::size_t s = 0; s < k.size(); ++s) grad.stiffness[s] *= k[s];
  return L;
}

// 5 x 5 cloth, 20 x 20 cm, 25 g, random log-stiffness around 60 N/m and dashpots, two corners
// swung along a polynomial path and released at step 120 of 200 (dt 5e-4 s)
Problem make_problem(bool floor, std::uint64_t seed) {
  Problem p;
  GridSpec g = test_cloth(5);
  g.total_mass = 0.025;
  g.origin = Vec3(0.0, floor ? 0.02 : 0.5, 0.0);
  p.model = build_grid(g);
  p.model.anchors = {{0, 120}, {4, 120}};
  p.model.dt = 5e-4;
  p.model.damping = 0.5;
  p.steps = 200;
  Rng rng(seed);
  for (Spring& s : p.model.springs) {
    p.log_k.push_back(dm::log(60.0) + 0.5 * rng.uniform(-1.0, 1.0));
    s.damping = 0.01 * rng.uniform(0.5, 1.5);
  }
  const double vy = floor ? -0.1 : -1.0;  // the anchors stay above the floor in the contact case
  p.path = anchor_path_from(p.model, p.steps, [&](int a, double t) -> Vec3 {
    const Vec3 r = p.model.rest_position[p.model.anchors[a].vertex];
    return r + Vec3(0.3 * t + (a == 0 ? 0.5 : -0.3) * t * t, vy * t + 2.0 * t * t, 0.5 * t);
  });
  p.s0 = rest_state(p.model);
  for (Vec3& v : p.s0.v)
    v = Vec3(rng.uniform(-0.2, 0.2), rng.uniform(-0.5, 0.0) - (floor ? 0.3 : 0.0), rng.uniform(-0.2, 0.2));
  for (int i = 0; i < p.model.vertices(); ++i)
    p.target.push_back(p.model.rest_position[i] + Vec3(0.03, floor ? -0.02 : -0.05, 0.02));
  if (floor) p.model.surfaces = {PlaneSurface::floor()};
  return p;
}

// Which contacts the episode on `tape` made: one byte per (step, vertex, surface), 1 where the
// vertex was at or inside the surface moving inward (the projection acted). Two episodes with
// the same pattern lie on the same smooth piece of the discrete map.
std::vector<std::uint8_t> contact_pattern(const Problem& p, const ClothTape& tape) {
  std::vector<std::uint8_t> pattern;
  for (int t = 0; t < p.steps; ++t)
    for (int i = 0; i < p.model.vertices(); ++i) {
      Vec3 v = tape.pre_contact_v(t)[i];
      for (const auto& surface : p.model.surfaces) {
        const SurfaceSample q = surface->sample(t, tape.x(t)[i]);
        const Vec3 w = v - q.velocity;
        const double wn = w.dot(q.normal);
        const bool active = q.distance <= 0.0 && wn < 0.0;
        if (active) v = q.velocity + p.model.tangential_keep * (w - wn * q.normal);
        pattern.push_back(active ? 1 : 0);
      }
    }
  return pattern;
}

struct GroupError {
  double worst = 0.0;  // worst |a - c| / (|c| + 1e-3 max |c|) over the compared coordinates
  double max_central = 0.0;
  int coords = 0;
  int across_events = 0;  // coordinates whose window [-h, h] changes the contact pattern
};

// Central differences of loss_of over one group of coordinates against the analytic values, on
// the coordinates whose difference window stays on the base point's smooth piece (same contact
// pattern at -h, 0 and +h); the others are counted: there the loss has a kink (the sign test
// w_n < 0 switches) or a jump (the distance test switches), which the analytic derivative, the
// one-sided derivative of the base point's piece, does not see by design.
GroupError check_group(const Problem& base, int count, double h,
                       const std::function<void(Problem&, int, double)>& perturb,
                       const std::function<double(int)>& analytic, const std::string& name) {
  ClothTape tape;
  loss_of(base, tape);
  const std::vector<std::uint8_t> base_pattern = contact_pattern(base, tape);
  std::vector<double> central(count);
  std::vector<char> smooth(count, 1);
  GroupError r;
  r.coords = count;
  for (int i = 0; i < count; ++i) {
    Problem hi = base, lo = base;
    perturb(hi, i, h);
    perturb(lo, i, -h);
    const double l_hi = loss_of(hi, tape);
    const bool same_hi = contact_pattern(hi, tape) == base_pattern;
    const double l_lo = loss_of(lo, tape);
    const bool same_lo = contact_pattern(lo, tape) == base_pattern;
    central[i] = (l_hi - l_lo) / (2.0 * h);
    if (!(same_hi && same_lo)) {
      smooth[i] = 0;
      ++r.across_events;
      continue;
    }
    r.max_central = std::max(r.max_central, std::abs(central[i]));
  }
  int worst_i = -1;
  for (int i = 0; i < count; ++i) {
    if (!smooth[i]) continue;
    const double err = std::abs(analytic(i) - central[i]) / (std::abs(central[i]) + 1e-3 * r.max_central);
    if (err > r.worst) r.worst = err, worst_i = i;
  }
  std::printf(
      "[cloth]   %-14s %4d coords (%d across a contact event), h %.0e, max |dL| %.3e, worst relative "
      "error %.2e (coord %d: analytic %.9e, central %.9e)\n",
      name.c_str(), count, r.across_events, h, r.max_central, r.worst, worst_i, worst_i >= 0 ? analytic(worst_i) : 0.0,
      worst_i >= 0 ? central[worst_i] : 0.0);
  return r;
}

// Every coordinate of every gradient of the problem. Steps: 1e-6 for positions (initial x, the
// anchor path, the ball), 1e-5 for the velocity, log-stiffness and dashpot groups, whose
// derivatives are 100 to 1000 times smaller, so that round-off (measured ~4e-10 absolute in a
// central difference at h = 1e-6) stays far below the error floor 1e-3 max |dL| of the group.
void expect_gradient_matches(const Problem& p, double tolerance, double max_across_fraction) {
  ClothTape tape;
  ClothGradient g;
  loss_and_gradient(p, tape, g);
  const int n = p.model.vertices(), ns = p.model.spring_count();
  std::vector<GroupError> errs;
  errs.push_back(check_group(
      p, 3 * n, 1e-5, [](Problem& q, int i, double d) { q.s0.v[i / 3][i % 3] += d; },
      [&](int i) { return g.v0[i / 3][i % 3]; }, "initial v"));
  errs.push_back(check_group(
      p, 3 * n, 1e-6, [](Problem& q, int i, double d) { q.s0.x[i / 3][i % 3] += d; },
      [&](int i) { return g.x0[i / 3][i % 3]; }, "initial x"));
  errs.push_back(check_group(
      p, ns, 1e-5, [](Problem& q, int i, double d) { q.log_k[i] += d; }, [&](int i) { return g.stiffness[i]; },
      "log stiffness"));
  errs.push_back(check_group(
      p, ns, 1e-5, [](Problem& q, int i, double d) { q.model.springs[i].damping += d; },
      [&](int i) { return g.damping[i]; }, "spring damping"));
  errs.push_back(check_group(
      p, 3 * static_cast<int>(p.path.size()), 1e-6, [](Problem& q, int i, double d) { q.path[i / 3][i % 3] += d; },
      [&](int i) { return g.anchor_path[i / 3][i % 3]; }, "anchor path"));
  if (p.ball >= 0) {
    errs.push_back(check_group(
        p, 9, 1e-6,
        [&](Problem& q, int i, double d) {
          const auto& ball = dynamic_cast<const Ball&>(*q.model.surfaces[p.ball]);
          auto prm = ball.p_;
          prm[i] += d;
          q.model.surfaces[p.ball] = std::make_shared<Ball>(prm, ball.r_);
        },
        [&](int i) { return g.surface_params[p.ball][i]; }, "ball params"));
  }
  for (const GroupError& e : errs) {
    EXPECT_GT(e.max_central, 1e-4);  // the group matters to the loss
    EXPECT_LE(e.worst, tolerance);
    // a few coordinates may sit next to a contact switch; at least one is always allowed
    EXPECT_LE(e.across_events, std::max(1.0, max_across_fraction * e.coords));
  }
}

// contact events of an episode: a vertex at or below a surface moving inward before projection
int contacts_of(const Problem& p) {
  ClothTape tape;
  loss_of(p, tape);
  const auto pattern = contact_pattern(p, tape);
  return static_cast<int>(std::count(pattern.begin(), pattern.end(), std::uint8_t{1}));
}

// Tolerance 1e-4 on |analytic - central| / (|central| + 1e-3 max |central|): with the steps
// above the truncation error h^2 |L'''| / 6 is ~3e-7 relative (measured on the anchor path at
// h = 1e-6) and the round-off ~1e-10 absolute against floors >= 1e-5: both well below 1e-4.
constexpr double kGradTolerance = 1e-4;

TEST(ClothTapeTest, ContactFlagsAreTheProjectionsThatActed) {
  // the reverse pass samples a surface again only where the tape's flag says it acted: the flags
  // must equal the independent replay above, bit k for surface k
  const Problem p = make_problem(true, 4);
  ClothTape tape;
  loss_of(p, tape);
  const auto pattern = contact_pattern(p, tape);
  const std::size_t ns = p.model.surfaces.size();
  int set = 0;
  for (int t = 0; t < p.steps; ++t)
    for (int i = 0; i < p.model.vertices(); ++i)
      for (std::size_t k = 0; k < ns; ++k) {
        const bool flag = (tape.contact(t)[i] >> k) & 1u;
        ASSERT_EQ(flag, pattern[(std::size_t(t) * p.model.vertices() + i) * ns + k] == 1) << t << " " << i;
        set += flag;
      }
  EXPECT_GT(set, 100);
}

TEST(ClothGradient, MatchesCentralDifferencesWithoutContact) {
  const Problem p = make_problem(false, 3);
  std::printf("[cloth] gradient, no contact:\n");
  expect_gradient_matches(p, kGradTolerance, 0.0);
}

TEST(ClothGradient, MatchesCentralDifferencesWithFloorContact) {
  const Problem p = make_problem(true, 4);
  const int contacts = contacts_of(p);
  std::printf("[cloth] gradient, floor contact (%d vertex-steps in contact):\n", contacts);
  ASSERT_GT(contacts, 100);  // the episode really has contact
  expect_gradient_matches(p, kGradTolerance, 0.1);
}

TEST(ClothGradient, MatchesCentralDifferencesOnASpinningBallWithFriction) {
  // the cloth falls onto a ball of radius 5 cm under its centre that translates and spins, with
  // tangential_keep 0.7: every term of the contact reverse (dn/dx, du/dx, surface parameters)
  Problem p = make_problem(false, 5);
  for (Vec3& x : p.s0.x) x.y() = 0.06;
  p.model.rest_position = p.s0.x;
  for (int i = 0; i < p.model.vertices(); ++i) p.target[i] = p.s0.x[i] + Vec3(0.03, -0.02, 0.02);
  p.model.tangential_keep = 0.7;
  p.model.surfaces = {
      std::make_shared<Ball>(std::array<double, 9>{0.1, 0.0, 0.1, 0.05, 0.1, -0.02, 1.0, 3.0, -2.0}, 0.05)};
  p.ball = 0;
  p.path = anchor_path_from(p.model, p.steps, [&](int a, double t) -> Vec3 {
    return p.model.rest_position[p.model.anchors[a].vertex] + Vec3(0.0, -0.05 * t, 0.1 * t);
  });
  const int contacts = contacts_of(p);
  std::printf("[cloth] gradient, spinning ball (%d vertex-steps in contact):\n", contacts);
  ASSERT_GT(contacts, 50);
  expect_gradient_matches(p, kGradTolerance, 0.1);
}

// ---------------------------------------------------------------------------------------------
// determinism and validation

TEST(ClothDeterminism, IdenticalRerunsGiveTheSameBits) {
  const Problem p = make_problem(true, 4);
  ClothTape t1, t2;
  ClothGradient g1, g2;
  const double l1 = loss_and_gradient(p, t1, g1);
  loss_of(make_problem(false, 9), t2);  // the second tape held another episode before
  const double l2 = loss_and_gradient(p, t2, g2);
  EXPECT_EQ(std::memcmp(&l1, &l2, sizeof l1), 0);
  auto same = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
  };
  auto same_d = [](const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
  };
  EXPECT_TRUE(same(g1.x0, g2.x0));
  EXPECT_TRUE(same(g1.v0, g2.v0));
  EXPECT_TRUE(same(g1.anchor_path, g2.anchor_path));
  EXPECT_TRUE(same_d(g1.stiffness, g2.stiffness));
  EXPECT_TRUE(same_d(g1.damping, g2.damping));
  for (int t = 0; t <= p.steps; ++t) {
    EXPECT_EQ(std::memcmp(t1.x(t).data(), t2.x(t).data(), t1.x(t).size_bytes()), 0) << t;
    EXPECT_EQ(std::memcmp(t1.v(t).data(), t2.v(t).data(), t1.v(t).size_bytes()), 0) << t;
  }
}

TEST(ClothModelTest, GridHasTheDocumentedSpringsAndValidationNamesTheField) {
  const ClothModel m = build_grid(test_cloth(5));
  // structural 2 * 5 * 4, shear 2 * 4 * 4, bending 2 * 5 * 3
  EXPECT_EQ(m.spring_count(), 40 + 32 + 30);
  EXPECT_EQ(m.springs[0].kind, SpringKind::structural);
  EXPECT_EQ(m.springs[40].kind, SpringKind::shear);
  EXPECT_EQ(m.springs[72].kind, SpringKind::bending);
  EXPECT_DOUBLE_EQ(m.springs[40].rest_length, std::sqrt(2.0) * 0.05);
  EXPECT_DOUBLE_EQ(m.springs[72].rest_length, 0.1);
  ClothModel bad = m;
  bad.springs[3].rest_length = 0.0;
  try {
    bad.validate();
    FAIL() << "expected ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("springs[3].rest_length"), std::string::npos) << e.what();
  }
  bad = m;
  bad.anchors = {{2}, {2}};
  EXPECT_THROW(bad.validate(), std::exception);
}

}  // namespace
}  // namespace dsb::cloth
