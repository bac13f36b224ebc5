// The budget wrapper and one run: counting, recording, best-so-far, failed episodes, rejection
// of points outside the box, and identical reruns.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.hpp"
#include "envs/registry.hpp"
#include "envs/synthetic/synthetic.hpp"
#include "harness/run/budget.hpp"
#include "harness/plan/grid.hpp"
#include "harness/run/runner.hpp"
#include "optimizers/registry.hpp"
#include "tests/support/reach_env.hpp"

namespace dsb {
namespace {

// a 1-D env that blows up (NaN) for x > 0.5
class FragileEnv : public Env {
 public:
  FragileEnv() : Env(EnvInfo{"fragile", 1, true, false, false, 0.0, ""}) {}
  nlohmann::json config() const override { return {{"fragile", true}}; }

 protected:
  double rollout(std::span<const double> x, Workspace&, ThreadTeam&) const override {
    return x[0] > 0.5 ? std::numeric_limits<double>::quiet_NaN() : (x[0] - 0.2) * (x[0] - 0.2);
  }
  double rollout_with_grad(std::span<const double> x, std::span<double> g, Workspace& ws,
                           ThreadTeam& team) const override {
    g[0] = 2.0 * (x[0] - 0.2);
    return rollout(x, ws, team);
  }
};

TEST(Budget, RecordsEveryEpisodeAndStopsAtTheBudget) {
  auto classic = *synthetic_config_from_name("sphere-3");
  classic.x_opt.assign(3, 0.0);  // unshifted: loss = 25 |x|^2
  const auto env = make_synthetic_env("sphere-3", classic);
  BudgetedObjective f(*env, 3);
  const std::vector<double> a{0.5, 0.0, 0.0}, b{0.1, 0.0, 0.0}, c{0.3, 0.0, 0.0};
  EXPECT_DOUBLE_EQ(f.value(a), 6.25);
  std::vector<double> g(3);
  EXPECT_DOUBLE_EQ(f.value_and_grad(b, g), 0.25);
  EXPECT_DOUBLE_EQ(f.value(c), 2.25);
  EXPECT_THROW(f.value(a), BudgetExhausted);
  ASSERT_EQ(f.evals().size(), 3u);
  EXPECT_EQ(f.evals()[1].episode, 1);
  EXPECT_TRUE(f.evals()[1].used_grad);
  EXPECT_FALSE(f.evals()[2].used_grad);
  EXPECT_DOUBLE_EQ(f.evals()[2].best_loss, 0.25);
  EXPECT_DOUBLE_EQ(f.best_loss(), 0.25);
  EXPECT_EQ(f.best_x(), b);
}

TEST(Budget, FailedEpisodeIsRecordedAsNaNAndNeverBest) {
  FragileEnv env;
  BudgetedObjective f(env, 4);
  const std::vector<double> bad{0.9}, good{0.0};
  EXPECT_EQ(f.value(bad), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(f.best_loss()));
  EXPECT_DOUBLE_EQ(f.value(good), 0.04);
  std::vector<double> g(1, 123.0);
  EXPECT_EQ(f.value_and_grad(bad, g), std::numeric_limits<double>::infinity());
  EXPECT_EQ(g[0], 0.0);
  EXPECT_EQ(f.failed_episodes(), 2);
  EXPECT_TRUE(std::isnan(f.evals()[0].loss));
  EXPECT_DOUBLE_EQ(f.evals()[2].best_loss, 0.04);
}

TEST(Budget, RejectsPointsOutsideTheBoxOrOfTheWrongSize) {
  const auto env = make_env("sphere-2");
  BudgetedObjective f(*env, 10);
  EXPECT_THROW(f.value(std::vector<double>{1.5, 0.0}), std::logic_error);
  EXPECT_THROW(f.value(std::vector<double>{std::nan(""), 0.0}), std::logic_error);
  EXPECT_THROW(f.value(std::vector<double>{0.0}), std::logic_error);
  EXPECT_EQ(f.used(), 0);
}

TEST(ExecuteRun, FullBudgetAndIdenticalReruns) {
  const auto env = make_env("cartpole3");
  RunSpec spec{"cartpole3", "cmaes", 0, 120, 77};
  auto opt1 = make_optimizer("cmaes"), opt2 = make_optimizer("cmaes");
  const RunResult a = execute_run(spec, *env, *opt1);
  const RunResult b = execute_run(spec, *env, *opt2);
  EXPECT_EQ(a.status, RunStatus::done);
  EXPECT_EQ(a.episodes, 120);
  ASSERT_EQ(a.evals.size(), b.evals.size());
  for (std::size_t i = 0; i < a.evals.size(); ++i) EXPECT_EQ(a.evals[i].loss, b.evals[i].loss);
  EXPECT_EQ(a.best_x, b.best_x);
  EXPECT_EQ(a.best_loss, env->loss(a.best_x));
}

TEST(ExecuteRun, OptimizerErrorBecomesAFailedRun) {
  // gd on an env whose gradient call throws: recorded as failed with the message, no crash
  class Throwing : public FragileEnv {
    double rollout_with_grad(std::span<const double>, std::span<double>, Workspace&, ThreadTeam&) const override {
      throw std::runtime_error("solver diverged");
    }
  } env;
  auto gd = make_optimizer("gd");
  const RunResult r = execute_run({"fragile", "gd", 0, 10, 1}, env, *gd);
  EXPECT_EQ(r.status, RunStatus::failed);
  EXPECT_NE(r.error.find("solver diverged"), std::string::npos);
}

// the records of a batch equal those of one value() call per point, whatever the team size, and
// a batch that overruns the budget records the points that fit, then throws BudgetExhausted
std::vector<EvalRecord> batch_records(const Env& env, std::span<const double> xs, std::size_t n, std::int64_t budget,
                                      int threads, bool batched, bool* exhausted) {
  ThreadTeam team(threads);
  BudgetedObjective f(env, budget, nullptr, &team);
  std::vector<double> out(n);
  *exhausted = false;
  try {
    if (batched) {
      f.values(xs, out);
    } else {
      const std::size_t d = static_cast<std::size_t>(env.dim());
      for (std::size_t i = 0; i < n; ++i) out[i] = f.value(xs.subspan(i * d, d));
    }
  } catch (const BudgetExhausted&) {
    *exhausted = true;
  }
  return f.evals();
}

TEST(Budget, BatchRecordsEqualOneAtATimeForAnyTeamSize) {
  const auto env = make_env("rastrigin-5");
  Rng rng(5);
  const std::size_t n = 23;
  std::vector<double> xs(n * 5);
  for (double& v : xs) v = rng.uniform(-1.0, 1.0);
  for (const std::int64_t budget : {std::int64_t{100}, std::int64_t{17}}) {
    bool ex_serial = false;
    const auto serial = batch_records(*env, xs, n, budget, 1, false, &ex_serial);
    for (const int threads : {1, 2, 3}) {
      bool ex = false;
      const auto batch = batch_records(*env, xs, n, budget, threads, true, &ex);
      EXPECT_EQ(ex, ex_serial);
      ASSERT_EQ(batch.size(), serial.size()) << threads << " threads, budget " << budget;
      for (std::size_t i = 0; i < serial.size(); ++i) {
        EXPECT_EQ(batch[i].episode, serial[i].episode);
        EXPECT_EQ(batch[i].loss, serial[i].loss) << "episode " << i << ", " << threads << " threads";
        EXPECT_EQ(batch[i].best_loss, serial[i].best_loss);
      }
    }
  }
  bool ex = false;
  EXPECT_EQ(batch_records(*env, xs, n, 17, 2, true, &ex).size(), 17u);
  EXPECT_TRUE(ex);
}

TEST(Budget, BatchWithAFailedEpisodeAndABadPoint) {
  FragileEnv env;
  ThreadTeam team(2);
  BudgetedObjective f(env, 10, nullptr, &team);
  std::vector<double> out(3);
  f.values(std::vector<double>{0.0, 0.9, 0.2}, out);
  EXPECT_DOUBLE_EQ(out[0], 0.04);
  EXPECT_EQ(out[1], std::numeric_limits<double>::infinity());
  EXPECT_EQ(out[2], 0.0);
  EXPECT_EQ(f.failed_episodes(), 1);
  // a point outside the box: the points before it are recorded, as one-at-a-time would
  EXPECT_THROW(f.values(std::vector<double>{0.1, 1.5, 0.3}, out), std::logic_error);
  EXPECT_EQ(f.used(), 4);
  EXPECT_DOUBLE_EQ(f.evals()[3].loss, (0.1 - 0.2) * (0.1 - 0.2));
}

TEST(ExecuteRun, RunsAreBitIdenticalForAnyTeamSize) {
  // cmaes, boleap and random evaluate batches: 1, 2 and 3 threads give the same records
  for (const std::string opt_name : {"cmaes", "random", "boleap"}) {
    const auto env = make_env("rosenbrock-10");
    RunSpec spec{"rosenbrock-10", opt_name, 0, 150, per_run_seed("rosenbrock-10", opt_name, 0)};
    std::vector<RunResult> results;
    for (const int threads : {1, 2, 3}) {
      ThreadTeam team(threads);
      auto opt = make_optimizer(opt_name);
      results.push_back(execute_run(spec, *env, *opt, nullptr, &team));
    }
    for (const auto& r : results) {
      ASSERT_EQ(r.status, RunStatus::done) << opt_name << ": " << r.error;
      ASSERT_EQ(r.evals.size(), results[0].evals.size());
      for (std::size_t i = 0; i < r.evals.size(); ++i)
        ASSERT_EQ(r.evals[i].loss, results[0].evals[i].loss) << opt_name << " episode " << i;
    }
  }
}

}  // namespace
}  // namespace dsb

namespace dsb {
namespace {

// an RL episode through the budget: decisions of action_repeat env steps, recorded when done
TEST(BudgetRl, EpisodesAreRecordedWithTheEnvsFinalLossAndCountAgainstTheBudget) {
  for (const std::string name : {"cartpole1", "flip"}) {
    const auto env = make_env(name);
    BudgetedObjective f(*env, 3);
    ASSERT_TRUE(f.has_rl());
    const RlSpec spec = f.rl_spec();
    const auto direct = env->make_rl();
    EXPECT_EQ(spec.observation_dim, direct->observation_dim());
    EXPECT_EQ(spec.action_dim, direct->action_dim());
    EXPECT_EQ(spec.action_repeat, name == "cartpole1" ? 1 : 5);  // the seed's action repeats
    EXPECT_EQ(spec.decisions, (direct->horizon() + spec.action_repeat - 1) / spec.action_repeat);
    std::vector<double> obs(spec.observation_dim), action(spec.action_dim);
    Rng rng(5);
    for (int episode = 0; episode < 3; ++episode) {
      f.rl_reset(obs);
      direct->reset();
      EXPECT_EQ(obs, direct->observe());
      RlStep r;
      int decisions = 0;
      while (!r.done) {
        for (double& a : action) a = rng.uniform(-1.0, 1.0);
        r = f.rl_step(action, obs);
        for (int k = 0; k < spec.action_repeat && !direct->done(); ++k) direct->step(action);
        EXPECT_EQ(obs, direct->observe());
        ++decisions;
        ASSERT_LE(decisions, spec.decisions);
      }
      EXPECT_EQ(decisions, spec.decisions) << name;
      EXPECT_EQ(r.loss, direct->final_loss()) << name;  // finite here: recorded as is
      ASSERT_EQ(f.used(), episode + 1);
      EXPECT_EQ(f.evals().back().loss, r.loss);
      EXPECT_FALSE(f.evals().back().used_grad);
    }
    // the budget is spent: no fourth episode, and nothing more is recorded
    EXPECT_THROW(f.rl_reset(obs), BudgetExhausted);
    EXPECT_EQ(f.used(), 3);
  }
}

// Listens without committing (the journal is taken at the end).
class QuietListener : public EpisodeListener {
 public:
  void episode_finished(BudgetedObjective&, bool) override {}
};

TEST(BudgetRl, AnRlEpisodeKeepsTheEnvsMetricAndReplaysIt) {
  const auto env = make_env("fluid-h5");  // metric cube_height; one decision an episode
  const std::vector<double> action = {0.4, -0.3};
  QuietListener listener;
  BudgetedObjective live(*env, 2);
  live.set_listener(&listener, nullptr);
  std::vector<double> obs(live.rl_spec().observation_dim);
  for (int episode = 0; episode < 2; ++episode) {
    live.rl_reset(obs);
    for (RlStep r; !r.done;) r = live.rl_step(action, obs);
  }
  const auto direct = env->make_rl();
  direct->reset();
  while (!direct->done()) direct->step(action);
  ASSERT_EQ(live.evals().size(), 2u);
  const double metric = live.evals()[0].metric;
  EXPECT_TRUE(std::isfinite(metric));
  EXPECT_GT(metric, 0.0);  // the cube's centre is above the tank floor
  EXPECT_EQ(metric, direct->final_metric());
  EXPECT_EQ(live.evals()[1].metric, metric);
  std::int64_t first = 0;
  const std::vector<ReplayEntry> journal = live.take_journal(first);
  // replayed from the journal: the same metric; from a journal written before the metric was
  // kept (3 values before the observation), NaN and the same losses
  for (const bool old_layout : {false, true}) {
    std::vector<ReplayEntry> entries = journal;
    if (old_layout)
      for (auto& e : entries)
        if (e.kind == ReplayKind::rl_step) e.payload.erase(e.payload.begin() + 3);
    BudgetedObjective replayed(*env, 2);
    replayed.set_replay(entries, 2);
    for (int episode = 0; episode < 2; ++episode) {
      replayed.rl_reset(obs);
      for (RlStep r; !r.done;) r = replayed.rl_step(action, obs);
    }
    EXPECT_EQ(replayed.replayed_episodes(), 2) << old_layout;
    ASSERT_EQ(replayed.evals().size(), 2u);
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(replayed.evals()[k].loss, live.evals()[k].loss) << old_layout;
      if (old_layout) {
        EXPECT_TRUE(std::isnan(replayed.evals()[k].metric));
      } else {
        EXPECT_EQ(replayed.evals()[k].metric, metric);
      }
    }
  }
}

TEST(BudgetRl, TheTestReachEnvsLossIsItsRlEpisode) {
  testing::ReachEnv env;
  BudgetedObjective f(env, 4);
  const RlSpec spec = f.rl_spec();
  EXPECT_EQ(spec.decisions, 20);
  std::vector<double> obs(2), a(1), x(20);
  Rng rng(2);
  for (int e = 0; e < 4; ++e) {
    f.rl_reset(obs);
    RlStep r;
    for (int t = 0; !r.done; ++t) {
      a[0] = x[t] = rng.uniform(-1.0, 1.0);
      r = f.rl_step(a, obs);
    }
    EXPECT_EQ(r.loss, env.loss(x));
  }
  EXPECT_LT(env.loss(std::vector<double>(20, 0.5)),
            1e-15);  // a = 0.5 throughout reaches the target (round-off: 2.2e-16)
}

// an RL env whose simulation blows up at its third step (NaN state) and never says done early
class BlowsUpEnv : public Env {
 public:
  BlowsUpEnv() : Env(EnvInfo{"blows-up", 10, false, true, false, 1e-6, ""}) {}
  nlohmann::json config() const override { return nlohmann::json::object(); }
  class Rl : public RlEnv {
   public:
    int observation_dim() const override { return 2; }
    int action_dim() const override { return 1; }
    int horizon() const override { return 10; }
    int action_repeat() const override { return 1; }
    void reset() override { t_ = 0, s_ = 0.0; }
    std::vector<double> observe() const override { return {s_, static_cast<double>(t_)}; }
    void step(std::span<const double>) override {
      ++t_;
      s_ = t_ >= 3 ? std::numeric_limits<double>::quiet_NaN() : s_ + 1.0;
    }
    bool done() const override { return t_ >= 10; }
    double final_loss() const override { return s_; }

   private:
    int t_ = 0;
    double s_ = 0.0;
  };
  std::unique_ptr<RlEnv> make_rl() const override { return std::make_unique<Rl>(); }

 protected:
  double rollout(std::span<const double>, Workspace&, ThreadTeam&) const override { return 0.0; }
  double rollout_with_grad(std::span<const double>, std::span<double>, Workspace&, ThreadTeam&) const override {
    return 0.0;
  }
};

TEST(BudgetRl, ABlownUpSimulationEndsItsEpisodeAsAFailure) {
  BlowsUpEnv env;
  BudgetedObjective f(env, 2);
  std::vector<double> obs(2), a{0.0};
  for (int e = 0; e < 2; ++e) {
    f.rl_reset(obs);
    RlStep r;
    int decisions = 0;
    while (!r.done) {
      r = f.rl_step(a, obs);
      ++decisions;
    }
    EXPECT_EQ(decisions, 3);  // ends where the state went NaN, not at the horizon
    EXPECT_EQ(r.loss, std::numeric_limits<double>::infinity());
    EXPECT_EQ(obs, (std::vector<double>{0.0, 0.0}));  // the optimizer never sees NaN
    EXPECT_TRUE(std::isnan(f.evals().back().loss));
  }
  EXPECT_EQ(f.used(), 2);
  EXPECT_EQ(f.failed_episodes(), 2);
  EXPECT_THROW(f.rl_reset(obs), BudgetExhausted);
}

TEST(BudgetRl, EveryStartedEpisodeIsFinishedAndActionsAreChecked) {
  const auto env = make_env("cartpole1");
  BudgetedObjective f(*env, 5);
  const RlSpec spec = f.rl_spec();
  std::vector<double> obs(spec.observation_dim), action(spec.action_dim, 0.0);
  EXPECT_THROW(f.rl_step(action, obs), std::logic_error);  // no open episode
  f.rl_reset(obs);
  f.rl_step(action, obs);
  // no restart mid-episode: the steps taken so far would be information nobody paid for
  EXPECT_THROW(f.rl_reset(obs), std::logic_error);
  std::vector<double> outside(spec.action_dim, 0.0), wrong(spec.action_dim + 1, 0.0);
  outside[1] = 1.5;
  EXPECT_THROW(f.rl_step(outside, obs), std::logic_error);
  EXPECT_THROW(f.rl_step(wrong, obs), std::logic_error);
  EXPECT_EQ(f.used(), 0);
  // an env without an RL view
  const auto sphere = make_env("sphere-10");
  BudgetedObjective g(*sphere, 5);
  EXPECT_FALSE(g.has_rl());
  EXPECT_THROW(g.rl_reset(obs), std::logic_error);
}

}  // namespace
}  // namespace dsb
