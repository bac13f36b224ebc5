// The RL learners' shared core (optimizers/rl/rl_core.hpp): the failed-episode stand-in under
// ppo's and sac's defaults against their rules written out by hand, the learning curve's blocks,
// the diagnostics keys both learners now share, the parameter digest against FNV-1a over the
// concatenated bytes, observation sanitizing, and one refusal for an objective without an RL view.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "optimizers/rl/ppo.hpp"
#include "optimizers/rl/rl_core.hpp"
#include "optimizers/rl/sac.hpp"
#include "support/function_objective.hpp"

namespace {

using dsb::EpisodeLosses;
using dsb::FailedEpisodeLoss;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ppo's rule before the core: -2 x |largest finite loss so far|, -2 before any
double ppo_rule(bool any, double worst) { return any ? 2.0 * std::abs(worst) : 2.0; }
// sac's rule before the core: max(factor x worst, floor), worst = -inf before any
double sac_rule(double worst, double factor, double floor) { return std::max(factor * worst, floor); }

TEST(FailedEpisodeLoss, PpoDefaultsKeepPposRule) {
  EpisodeLosses e(dsb::PpoConfig{}.failed_loss, 20);
  EXPECT_EQ(e.finish_episode(kInf), ppo_rule(false, 0.0));  // before any finite loss: 2
  EXPECT_EQ(e.finish_episode(0.3), 0.3);
  EXPECT_EQ(e.finish_episode(kNaN), ppo_rule(true, 0.3));  // 0.6: below sac's floor of 1
  EXPECT_EQ(e.finish_episode(0.1), 0.1);
  EXPECT_EQ(e.finish_episode(-kInf), ppo_rule(true, 0.3));  // the largest, not the last
  EXPECT_EQ(e.episodes(), 5);
  EXPECT_EQ(e.failed(), 3);
}

TEST(FailedEpisodeLoss, SacDefaultsKeepSacsRule) {
  const dsb::SacConfig cfg;
  EpisodeLosses e(cfg.failed_loss(), 1);
  EXPECT_EQ(e.finish_episode(kNaN), sac_rule(-kInf, 2.0, 1.0));  // 1
  EXPECT_EQ(e.finish_episode(0.3), 0.3);
  EXPECT_EQ(e.finish_episode(kInf), sac_rule(0.3, 2.0, 1.0));  // the floor: 1
  EXPECT_EQ(e.finish_episode(4.0), 4.0);
  EXPECT_EQ(e.finish_episode(kInf), sac_rule(4.0, 2.0, 1.0));  // 8
  dsb::SacConfig other;
  other.failed_loss_factor = 3.0;
  other.failed_loss_floor = 5.0;
  EpisodeLosses f(other.failed_loss(), 1);
  EXPECT_EQ(f.finish_episode(kInf), 5.0);  // the floor before any finite loss
  EXPECT_EQ(f.finish_episode(2.0), 2.0);
  EXPECT_EQ(f.finish_episode(kInf), 6.0);
}

TEST(FailedEpisodeLoss, ValidationNamesTheField) {
  auto message = [](FailedEpisodeLoss f) {
    try {
      f.validate("ppo");
    } catch (const dsb::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message({.factor = 0.5, .floor = 0.0, .before_any = 2.0}).find("'failed_loss_factor'"), std::string::npos);
  EXPECT_NE(message({.factor = 2.0, .floor = -1.0, .before_any = 2.0}).find("'failed_loss_floor'"), std::string::npos);
  EXPECT_NE(message({.factor = 2.0, .floor = 0.0, .before_any = 0.0}).find("'failed_loss_before_any'"),
            std::string::npos);
  EXPECT_EQ(message({.factor = 2.0, .floor = 0.0, .before_any = 2.0}), "");
  dsb::SacConfig sac;
  sac.failed_loss_floor = 0.0;  // sac's floor is its stand-in before any finite loss
  EXPECT_THROW(sac.validate(), dsb::ConfigError);
}

TEST(EpisodeLosses, LearningCurveByBlockAndTheSharedKeys) {
  EpisodeLosses e(FailedEpisodeLoss{}, 2);
  for (double loss : {1.0, 3.0, kInf, kNaN, 5.0}) e.finish_episode(loss);
  nlohmann::json d;
  e.put_diagnostics(d);
  EXPECT_EQ(d["episodes"], 5);
  EXPECT_EQ(d["failed_episodes"], 2);
  EXPECT_EQ(d["loss_block"], 2);
  ASSERT_EQ(d["mean_loss_per_block"].size(), 3u);  // the last block partial
  EXPECT_EQ(d["mean_loss_per_block"][0], 2.0);
  EXPECT_TRUE(d["mean_loss_per_block"][1].is_null());  // every episode failed
  EXPECT_EQ(d["mean_loss_per_block"][2], 5.0);
  EXPECT_EQ(d["mean_loss_per_block_truncated"], 0);
}

TEST(ParamsDigest, IsFnv1aOverTheConcatenatedBytes) {
  const std::vector<double> a{1.0, -2.5}, b{0.125};
  std::string bytes(3 * sizeof(double), '\0');
  std::memcpy(bytes.data(), a.data(), 2 * sizeof(double));
  std::memcpy(bytes.data() + 2 * sizeof(double), b.data(), sizeof(double));
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(dsb::fnv1a64(bytes)));
  EXPECT_EQ(dsb::params_digest({a, b}), hex);
  EXPECT_NE(dsb::params_digest({b, a}), hex);
}

TEST(SanitizeObservation, NanToZeroAndClamped) {
  std::vector<double> o{kNaN, kInf, -2e6, 3.0, -0.0};
  EXPECT_EQ(dsb::sanitize_observation(o), 3);
  EXPECT_EQ(o[0], 0.0);
  EXPECT_EQ(o[1], 1e6);
  EXPECT_EQ(o[2], -1e6);
  EXPECT_EQ(o[3], 3.0);
}

// Both learners refuse an objective without an RL view the same way: a UsageError naming them.
TEST(RequireRlView, PpoAndSacRefuseAlike) {
  for (const std::string name : {"ppo", "sac"}) {
    auto opt = name == "ppo" ? dsb::make_ppo() : dsb::make_sac();
    dsb::testing::FunctionObjective f(2, 10, [](std::span<const double>) { return 0.0; });
    dsb::Rng rng(1);
    try {
      opt->minimize(f, rng);
      ADD_FAILURE() << name << " ran without an RL view";
    } catch (const dsb::UsageError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(name + " needs an env with an RL view", 0), 0u) << e.what();
    }
    EXPECT_EQ(f.used(), 0);
  }
}

// ppo's config gains the failed-episode fields only when they differ from its defaults, so the
// default config (and its hash in every stored run key) is the one it always was.
TEST(PpoConfig, FailedLossFieldsOnlyWhenNotDefault) {
  const auto plain = dsb::PpoConfig{}.to_json();
  EXPECT_FALSE(plain.contains("failed_loss_factor"));
  dsb::PpoConfig other;
  other.failed_loss.floor = 1.0;
  const auto changed = other.to_json();
  EXPECT_EQ(changed["failed_loss_floor"], 1.0);
  EXPECT_EQ(changed["failed_loss_factor"], 2.0);
  EXPECT_EQ(changed["failed_loss_before_any"], 2.0);
}

}  // namespace
