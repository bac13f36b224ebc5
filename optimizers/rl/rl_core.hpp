#pragma once
// What the RL learners (`ppo`, `sac`) share: the RL view they require, the loss a failed episode
// is rewarded with, the learning curve and the episode counts in their diagnostics, the digest of
// what a run learned, observations made safe for the networks, and the layer sizes of their MLPs.
// Each learner keeps its own algorithm; anything both do the same way lives here.
#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "optimizers/core/objective.hpp"

namespace dsb {

// UsageError "NAME needs an env with an RL view (...)" unless the objective has one. The grid
// never pairs an RL learner with an env without one; this guards every other caller.
void require_rl_view(const Objective& f, const std::string& optimizer);

// [in, hidden..., out]: the layer sizes of an MLP
std::vector<int> mlp_layer_sizes(int in, const std::vector<int>& hidden, int out);

// The loss a failed episode (NaN or infinite) stands for in the learner's reward, so that a blow-up
// is the worst outcome without an infinite reward (the networks stay finite):
//   max(factor x |largest finite episode loss so far|, floor), or before_any while no episode of the
//   run has ended with a finite loss. The learners' defaults differ (ppo.hpp, sac.hpp say why).
struct FailedEpisodeLoss {
  double factor = 2.0;
  double floor = 1.0;
  double before_any = 1.0;
  // throws ConfigError(owner, "failed_loss_*", why)
  void validate(const std::string& owner) const;
};

// The episodes of one run as a learner sees them: counts, the failure stand-in, and the learning
// curve (mean finite loss per block of `block` episodes, the last block possibly partial).
class EpisodeLosses {
 public:
  EpisodeLosses(FailedEpisodeLoss failed, std::int64_t block);
  // notes an episode that ended with `loss` (as recorded by the budget); returns the loss the
  // learner's reward takes: `loss` when finite, the failed-episode stand-in otherwise
  double finish_episode(double loss);
  std::int64_t episodes() const { return episodes_; }
  std::int64_t failed() const { return failed_; }
  // "episodes", "failed_episodes", "loss_block", "mean_loss_per_block" (+ "_truncated": put_capped)
  void put_diagnostics(nlohmann::json& out) const;

 private:
  FailedEpisodeLoss failed_loss_;
  std::int64_t block_;
  std::int64_t episodes_ = 0, failed_ = 0;
  bool any_finite_ = false;
  double worst_finite_ = 0.0;
  std::vector<double> block_sum_;      // sum of finite losses per block
  std::vector<std::int64_t> block_n_;  // finite episodes per block
};

// Observations of a blown-up simulation may be NaN, infinite or huge, which would make every
// network parameter NaN: NaN becomes 0 and every component is clamped to [-1e6, 1e6]. Returns how
// many components changed.
int sanitize_observation(std::span<double> observation);

// 16 hex digits: FNV-1a 64 over the bytes of the parameter vectors, in order (what a run learned,
// for its diagnostics: equal runs give equal digests)
std::string params_digest(std::initializer_list<std::span<const double>> parts);

}  // namespace dsb
