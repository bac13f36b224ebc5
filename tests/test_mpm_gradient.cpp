// The MPM engine's reverse pass: action and initial-state gradients against central
// differences on a small model with every material and every primitive (short horizon, where
// differences are trustworthy), the checkpointed adjoint against the full-history one, and the
// same bits for any number of threads.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/mpm/episode.hpp"
#include "support/mpm_models.hpp"

namespace dsb {
namespace {

using mpm::Mat3;
using mpm::Vec3;
using testing::every_primitive_model;

std::vector<double> random_actions(const mpm::MpmModel& m, int env_steps, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<double> a(static_cast<std::size_t>(env_steps) * m.action_dim());
  for (auto& v : a) v = rng.uniform(-1.0, 1.0);
  return a;
}

TEST(MpmGradient, ActionsMatchCentralDifferencesWithEveryPrimitive) {
  const int env_steps = 2;
  const auto m = every_primitive_model(5);
  const testing::SmoothObjective objective;
  mpm::MpmWorkspace ws(m);
  for (std::uint64_t seed : {11u, 12u}) {
    auto a = random_actions(m, env_steps, seed);
    std::vector<double> grad(a.size());
    const double loss = mpm::run_episode_with_grad(m, ws, serial_team(), a, env_steps, objective, grad);
    ASSERT_TRUE(std::isfinite(loss));
    EXPECT_EQ(loss, mpm::run_episode(m, ws, serial_team(), a, env_steps, objective)) << "value paths agree";
    double gmax = 0.0;
    for (double g : grad) gmax = std::max(gmax, std::abs(g));
    const double h = 1e-6;
    std::vector<double> central(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      auto hi = a, lo = a;
      hi[i] += h;
      lo[i] -= h;
      central[i] = (mpm::run_episode(m, ws, serial_team(), hi, env_steps, objective) -
                    mpm::run_episode(m, ws, serial_team(), lo, env_steps, objective)) /
          (2 * h);
      EXPECT_NEAR(grad[i], central[i], 1e-5 * std::abs(central[i]) + 1e-4 * gmax)
          << "seed " << seed << " action " << i << " (step " << i / m.action_dim() << ", component "
          << i % m.action_dim() << ")";
    }
    // every primitive's contact is exercised: some action of each has a real gradient
    for (std::size_t pr = 0; pr < m.primitives.size(); ++pr) {
      double most = 0.0;
      for (int k = 0; k < env_steps; ++k)
        for (int c = 0; c < m.primitives[pr].action_dim(); ++c)
          most = std::max(most, std::abs(central[k * m.action_dim() + m.action_offset(pr) + c]));
      // beyond the loss's direct dependence on the pose (f . p per env step) there is contact
      EXPECT_GT(most, 0.0) << m.primitives[pr].name;
    }
  }
}

TEST(MpmGradient, InitialStateMatchesCentralDifferences) {
  const int env_steps = 2;
  auto m = every_primitive_model(5);
  const testing::SmoothObjective objective;
  const auto a = random_actions(m, env_steps, 21);
  mpm::MpmWorkspace ws(m);
  std::vector<double> grad(a.size());
  mpm::run_episode_with_grad(m, ws, serial_team(), a, env_steps, objective, grad);
  const std::vector<mpm::ParticleAdjoint> adj = ws.adj;
  // directions: every particle of a body moved along one state component at once
  struct Direction {
    int body;
    const char* what;
    int index;
  };
  const Direction dirs[] = {{0, "v", 0}, {1, "v", 1}, {2, "v", 2}, {0, "x", 1}, {1, "x", 0},
                            {0, "F", 4}, {1, "F", 1}, {0, "C", 3}, {2, "C", 0}, {2, "J", 0}};
  for (const auto& d : dirs) {
    const mpm::Body& body = m.bodies[d.body];
    auto component = [&](mpm::Particle& p) -> double& {
      if (d.what[0] == 'v') return p.v[d.index];
      if (d.what[0] == 'x') return p.x[d.index];
      if (d.what[0] == 'F') return p.F.data()[d.index];
      if (d.what[0] == 'C') return p.C.data()[d.index];
      return p.J;
    };
    double analytic = 0.0;
    for (int p = body.begin; p < body.end; ++p) {
      mpm::ParticleAdjoint g = adj[p];
      analytic += component(g);
    }
    // contact and friction are only piecewise smooth: the window must stay below the distance to
    // the nearest kink (measured: the fluid's J differences move by 1e-3 relative from h = 1e-6
    // to 1e-5 and settle at 1e-7; positions likewise); C's effect is tiny (dL/dC ~ 1e-6), so its
    // differences need a wider window to rise above rounding (1e-5: agreement to 1e-5 relative)
    const double h = (d.what[0] == 'x' || d.what[0] == 'J') ? 1e-7 : (d.what[0] == 'C' ? 1e-5 : 1e-6);
    const auto initial = m.initial;
    auto run_shifted = [&](double s) {
      for (int p = body.begin; p < body.end; ++p) component(m.initial[p]) += s;
      const double l = mpm::run_episode(m, ws, serial_team(), a, env_steps, objective);
      m.initial = initial;
      return l;
    };
    const double central = (run_shifted(h) - run_shifted(-h)) / (2 * h);
    EXPECT_NEAR(analytic, central, 1e-5 * std::abs(central) + 1e-9)
        << body.name << " d/d" << d.what << "[" << d.index << "]";
  }
}

TEST(MpmGradient, AnyTapeBudgetGivesTheSameBits) {
  // the reverse pass recomputes the env steps it did not tape from their checkpoints; that
  // repeats the forward pass exactly, so every budget gives the same loss, gradient and adjoints
  const int env_steps = 4;
  const auto m = every_primitive_model(4);
  const testing::SmoothObjective objective;
  const auto a = random_actions(m, env_steps, 31);
  mpm::MpmWorkspace ws(m);
  std::vector<double> g1(a.size()), g2(a.size()), g3(a.size());
  const double l1 = mpm::run_episode_with_grad(m, ws, serial_team(), a, env_steps, objective, g1, 0);
  EXPECT_EQ(ws.taped_env_steps, 0);
  const auto adj1 = ws.adj;
  const double l2 = mpm::run_episode_with_grad(m, ws, serial_team(), a, env_steps, objective, g2, mpm::kTapeEverything);
  EXPECT_EQ(ws.taped_env_steps, env_steps);
  // a budget of two and a half env steps' tapes keeps the first two
  const std::size_t per_step = ws.step_tape_bytes;
  ASSERT_GT(per_step, 0u);
  const double l3 = mpm::run_episode_with_grad(m, ws, serial_team(), a, env_steps, objective, g3, per_step * 5 / 2);
  EXPECT_EQ(ws.taped_env_steps, 2);
  EXPECT_EQ(l1, l2);
  EXPECT_EQ(l1, l3);
  EXPECT_EQ(g1, g2);
  EXPECT_EQ(g1, g3);
  for (int p = 0; p < m.particles(); ++p) {
    EXPECT_EQ(adj1[p].x, ws.adj[p].x) << p;
    EXPECT_EQ(adj1[p].F, ws.adj[p].F) << p;
  }
  // what one env step's tapes hold, as counted: at least the particles and their SVDs of S substeps
  EXPECT_GE(
      per_step,
      static_cast<std::size_t>(m.config.substeps) * m.particles() * (sizeof(mpm::Particle) + sizeof(mpm::SvdRecord)));
}

TEST(MpmGradient, SameBitsForAnyNumberOfThreads) {
  const int env_steps = 3;
  const auto m = every_primitive_model(4);
  const testing::SmoothObjective objective;
  const auto a = random_actions(m, env_steps, 41);
  std::vector<double> loss(3);
  std::vector<std::vector<double>> grads(3, std::vector<double>(a.size()));
  for (int t = 1; t <= 3; ++t) {
    ThreadTeam team(t);
    mpm::MpmWorkspace ws(m);
    loss[t - 1] = mpm::run_episode_with_grad(m, ws, team, a, env_steps, objective, grads[t - 1]);
  }
  EXPECT_EQ(loss[0], loss[1]);
  EXPECT_EQ(loss[0], loss[2]);
  EXPECT_EQ(grads[0], grads[1]);
  EXPECT_EQ(grads[0], grads[2]);
}

}  // namespace
}  // namespace dsb
