// The contract every optimizer keeps: each registered optimizer (optimizer_entries()) and an
// external one (ext:rs, examples/ext/random_search.py) run through execute_run, as a grid runs
// them, on a small env with a gradient and an RL view. Each must
//   - use exactly its budget, inside the box (the budget wrapper refuses a point outside it: such
//     a run ends failed);
//   - give the same bits from the same seed;
//   - give different runs from different seeds, unless its registration declares it seed-free
//     (SeedUse::never);
//   - survive NaN and infinite losses and NaN gradients (the run ends done, with its budget);
//   - stop cleanly when asked (interrupted, no error, before its budget) and resume from its
//     journal to the uninterrupted run's bits.
// Optimizer-specific behaviour is tested in each optimizer's own test.
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "harness/run/runner.hpp"
#include "optimizers/registry.hpp"

namespace dsb {
namespace {

constexpr int kDim = 4;
constexpr std::int64_t kBudget = 48;
constexpr std::int64_t kLateBudget = 300;

enum class Landscape {
  bowl,     // loss(x) = sum_i (x_i - c_i)^2, c_i = 0.3 - 0.1 i (dim 4)
  hostile,  // the bowl, NaN where x_0 > 0.5, +inf where x_0 < -0.5, a NaN gradient where x_1 > 0.6
  raised,   // 1e4 + bowl: relative tolerances (1e-10) end a local start early, and it restarts
};

// The RL view takes one action per step (horizon = dim, observation (t / dim, last action)) and
// ends with loss(actions).
class ContractEnv : public Env {
 public:
  explicit ContractEnv(Landscape landscape = Landscape::bowl) : Env(info_of()), landscape_(landscape) {}
  nlohmann::json config() const override { return {{"contract", static_cast<int>(landscape_)}}; }

  double loss_of(std::span<const double> x) const {
    const bool hostile = landscape_ == Landscape::hostile;
    if (hostile && x[0] > 0.5) return std::numeric_limits<double>::quiet_NaN();
    if (hostile && x[0] < -0.5) return std::numeric_limits<double>::infinity();
    double s = 0.0;
    for (int i = 0; i < kDim; ++i) s += (x[i] - centre(i)) * (x[i] - centre(i));
    return landscape_ == Landscape::raised ? 1e4 + s : s;
  }

  class Rl : public RlEnv {
   public:
    explicit Rl(const ContractEnv& env) : env_(env) {}
    int observation_dim() const override { return 2; }
    int action_dim() const override { return 1; }
    int horizon() const override { return kDim; }
    int action_repeat() const override { return 1; }
    void reset() override { actions_.clear(); }
    std::vector<double> observe() const override {
      return {static_cast<double>(actions_.size()) / kDim, actions_.empty() ? 0.0 : actions_.back()};
    }
    void step(std::span<const double> a) override { actions_.push_back(std::fmin(1.0, std::fmax(-1.0, a[0]))); }
    bool done() const override { return static_cast<int>(actions_.size()) >= kDim; }
    double final_loss() const override { return env_.loss_of(actions_); }

   private:
    const ContractEnv& env_;
    std::vector<double> actions_;
  };
  std::unique_ptr<RlEnv> make_rl() const override { return std::make_unique<Rl>(*this); }

 protected:
  double rollout(std::span<const double> x, Workspace&, ThreadTeam&) const override { return loss_of(x); }
  double rollout_with_grad(std::span<const double> x, std::span<double> g, Workspace&, ThreadTeam&) const override {
    for (int i = 0; i < kDim; ++i) g[i] = 2.0 * (x[i] - centre(i));
    if (landscape_ == Landscape::hostile && x[1] > 0.6) g[0] = std::numeric_limits<double>::quiet_NaN();
    return loss_of(x);
  }

 private:
  static double centre(int i) { return 0.3 - 0.1 * i; }
  static EnvInfo info_of() {
    EnvInfo info;
    info.name = "contract-test";
    info.dim = kDim;
    info.differentiable = true;
    info.rl = true;
    info.cost_hint_s = 1e-6;
    return info;
  }
  Landscape landscape_;
};

const std::string kExt = "ext:rs";

std::vector<std::string> contract_optimizers() {
  std::vector<std::string> names;
  for (const auto& e : optimizer_entries()) names.push_back(e.name);
  names.push_back(kExt);
  return names;
}

// the run spec as expand_grid resolves it: the registration, or the probed program
RunSpec spec_of(const std::string& optimizer, int seed, std::int64_t budget = kBudget) {
  RunSpec spec{"contract-test", optimizer, seed, budget, per_run_seed("contract-test", optimizer, seed)};
  if (optimizer == kExt) {
    static const ExtOptimizerSpec program = ext_probe(
        {"rs", std::string("/usr/bin/python3 ") + DSB_SOURCE_DIR + "/examples/ext/random_search.py", 60.0, "", ""});
    spec.ext = program;
  } else {
    spec.entry = &optimizer_entry(optimizer);
  }
  return spec;
}

bool seed_free(const std::string& optimizer) {
  return optimizer != kExt && optimizer_entry(optimizer).seed_use == SeedUse::never;
}

// every recorded bit of a run: each episode's loss, best so far, gradient use and metric, and
// the best point
std::vector<std::uint64_t> bits_of(const RunResult& r) {
  std::vector<std::uint64_t> bits;
  for (const EvalRecord& e : r.evals)
    for (double v : {e.loss, e.best_loss, e.used_grad ? 1.0 : 0.0, e.metric})
      bits.push_back(std::bit_cast<std::uint64_t>(v));
  for (double v : r.best_x) bits.push_back(std::bit_cast<std::uint64_t>(v));
  return bits;
}

// keeps every journal entry as a grid's run commits it, and asks the run to stop once it has
// `stop_after` episodes (0: never)
class JournalKeeper : public EpisodeListener {
 public:
  explicit JournalKeeper(std::int64_t stop_after = 0) : stop_after_(stop_after) {}
  void episode_finished(BudgetedObjective& objective, bool) override {
    keep(objective.take_journal(first_seq_));
    if (stop_after_ > 0 && objective.used() >= stop_after_) stop.store(true);
  }
  void keep(std::vector<ReplayEntry> entries) {
    for (auto& e : entries) journal.push_back(std::move(e));
  }
  std::atomic<bool> stop{false};
  std::vector<ReplayEntry> journal;

 private:
  std::int64_t stop_after_;
  std::int64_t first_seq_ = 0;
};

RunResult run(const RunSpec& spec, const Env& env, RunControl* control = nullptr) {
  return execute_run(spec, env, *spec.new_optimizer(), nullptr, nullptr, control);
}

// the plain env's run of seed 0, once per optimizer (several properties compare with it)
const RunResult& reference_run(const std::string& optimizer) {
  static std::map<std::string, RunResult> runs;
  auto it = runs.find(optimizer);
  if (it == runs.end()) {
    const ContractEnv env;
    it = runs.emplace(optimizer, run(spec_of(optimizer, 0), env)).first;
  }
  return it->second;
}

class EveryOptimizer : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryOptimizer, UsesExactlyTheBudgetInsideTheBox) {
  const RunResult& r = reference_run(GetParam());
  ASSERT_EQ(r.status, RunStatus::done) << r.error;  // a point outside the box fails the run
  EXPECT_EQ(r.episodes, kBudget);
  EXPECT_EQ(r.evals.size(), static_cast<std::size_t>(kBudget));
  EXPECT_EQ(r.failed_episodes, 0);
  // an RL learner's episodes are actions, not a point (its actions live in [-1, 1] by the RL view)
  const bool rl = GetParam() != kExt && optimizer_entry(GetParam()).needs_rl;
  ASSERT_EQ(r.best_x.size(), rl ? 0u : static_cast<std::size_t>(kDim));
  for (double v : r.best_x) {
    EXPECT_GE(v, -1.0);
    EXPECT_LE(v, 1.0);
  }
}

TEST_P(EveryOptimizer, TheSameSeedGivesTheSameBits) {
  const ContractEnv env;
  const RunResult again = run(spec_of(GetParam(), 0), env);
  ASSERT_EQ(again.status, RunStatus::done) << again.error;
  EXPECT_EQ(bits_of(again), bits_of(reference_run(GetParam())));
}

TEST_P(EveryOptimizer, AnotherSeedGivesAnotherRunUnlessSeedFree) {
  // an optimizer that first draws at a random restart (SeedUse::late) runs where its first start
  // ends early (DIRECT-L's tolerances never end it in 2,000 episodes on the bowl)
  const bool late = GetParam() != kExt && optimizer_entry(GetParam()).seed_use == SeedUse::late;
  const ContractEnv env(late ? Landscape::raised : Landscape::bowl);
  const std::int64_t budget = late ? kLateBudget : kBudget;
  const RunResult one = late ? run(spec_of(GetParam(), 0, budget), env) : reference_run(GetParam());
  const RunResult other = run(spec_of(GetParam(), 1, budget), env);
  ASSERT_EQ(other.status, RunStatus::done) << other.error;
  EXPECT_EQ(other.episodes, budget);
  if (seed_free(GetParam()))
    EXPECT_EQ(bits_of(other), bits_of(one)) << "declared seed-free (SeedUse::never)";
  else
    EXPECT_NE(bits_of(other), bits_of(one))
        << "seed 1 repeats seed 0: the optimizer ignores its seed, or must declare SeedUse::never";
}

TEST_P(EveryOptimizer, SurvivesNaNAndInfiniteLossesAndNaNGradients) {
  const ContractEnv hostile(Landscape::hostile);
  for (int seed : {0, 1}) {
    const RunResult r = run(spec_of(GetParam(), seed), hostile);
    ASSERT_EQ(r.status, RunStatus::done) << "seed " << seed << ": " << r.error;
    EXPECT_EQ(r.episodes, kBudget) << "seed " << seed;
    std::int64_t nan_losses = 0;
    for (const EvalRecord& e : r.evals) nan_losses += std::isnan(e.loss) ? 1 : 0;
    EXPECT_EQ(nan_losses, r.failed_episodes) << "a failed episode is stored as NULL (NaN)";
    if (r.failed_episodes < r.episodes) {
      EXPECT_TRUE(std::isfinite(r.best_loss)) << "seed " << seed;
    }
    // a uniform sampler lands in the hostile half of the box (|x_0| > 0.5) about 24 times in 48
    if (GetParam() == "random" || GetParam() == kExt) {
      EXPECT_GT(r.failed_episodes, 5) << "seed " << seed;
    }
  }
}

TEST_P(EveryOptimizer, StopsCleanlyWhenAskedAndResumesToTheSameBits) {
  const ContractEnv env;
  const RunSpec spec = spec_of(GetParam(), 0);
  constexpr std::int64_t kStopAfter = 17;
  JournalKeeper first(kStopAfter);
  RunControl stop_control{&first, &first.stop, {}, 0, 0};
  RunResult stopped = run(spec, env, &stop_control);
  first.keep(std::move(stopped.journal_tail));
  ASSERT_EQ(stopped.status, RunStatus::interrupted) << stopped.error;
  EXPECT_TRUE(stopped.error.empty()) << stopped.error;
  EXPECT_GE(stopped.episodes, kStopAfter);
  EXPECT_LT(stopped.episodes, kBudget);

  JournalKeeper second;
  RunControl resume{&second, &second.stop, std::move(first.journal), stopped.episodes, 0};
  const RunResult resumed = run(spec, env, &resume);
  ASSERT_EQ(resumed.status, RunStatus::done) << resumed.error;
  EXPECT_EQ(resumed.replayed_episodes, stopped.episodes);
  EXPECT_EQ(bits_of(resumed), bits_of(reference_run(GetParam())));
}

INSTANTIATE_TEST_SUITE_P(Optimizers, EveryOptimizer, ::testing::ValuesIn(contract_optimizers()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name;
                           for (char c : info.param) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name;
                         });

TEST(EveryOptimizer, CoversEveryRegisteredOptimizerAndAnExternalOne) {
  EXPECT_EQ(optimizer_entries().size(), 12u);
  EXPECT_EQ(contract_optimizers().size(), optimizer_entries().size() + 1);
  EXPECT_EQ(contract_optimizers().back(), kExt);
}

}  // namespace
}  // namespace dsb
