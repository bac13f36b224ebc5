#pragma once
// Replay buffer of the off-policy RL baseline (SAC), as SB3's ReplayBuffer with
// optimize_memory_usage = False and one env: a ring of transitions (obs, action, reward, next_obs,
// done), next_obs stored separately; once full, the oldest transition is overwritten. A batch is
// batch_size indices drawn uniformly WITH replacement from the stored transitions (SB3:
// np.random.randint(0, upper_bound, size=batch_size)), here with Rng::below in increasing draw
// order. All storage is allocated at construction: the owner sizes it (SAC: min(buffer_size,
// transitions the run can make)).
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "common/rng.hpp"

namespace dsb {

// one sampled batch, one column (or entry) per transition
struct ReplayBatch {
  Eigen::MatrixXd obs;               // obs_dim x batch
  Eigen::MatrixXd action;            // action_dim x batch
  Eigen::MatrixXd next_obs;          // obs_dim x batch
  std::vector<double> reward, done;  // batch each; done is 0 or 1
};

class ReplayBuffer {
 public:
  // throws std::invalid_argument for capacity < 1 or a dimension < 1
  ReplayBuffer(std::size_t capacity, int obs_dim, int action_dim)
      : capacity_(capacity), obs_dim_(obs_dim), action_dim_(action_dim) {
    if (capacity < 1 || obs_dim < 1 || action_dim < 1)
      throw std::invalid_argument("replay buffer: capacity and dimensions must be >= 1");
    const auto n = static_cast<Eigen::Index>(capacity);
    obs_.resize(obs_dim, n);
    next_obs_.resize(obs_dim, n);
    action_.resize(action_dim, n);
    reward_.assign(capacity, 0.0);
    done_.assign(capacity, 0.0);
  }

  std::size_t capacity() const { return capacity_; }
  std::size_t size() const { return full_ ? capacity_ : pos_; }
  int obs_dim() const { return obs_dim_; }
  int action_dim() const { return action_dim_; }

  void add(std::span<const double> obs, std::span<const double> action, double reward, std::span<const double> next_obs,
           bool done) {
    if (obs.size() != std::size_t(obs_dim_) || next_obs.size() != std::size_t(obs_dim_) ||
        action.size() != std::size_t(action_dim_))
      throw std::invalid_argument("replay buffer: transition has the wrong dimensions");
    const auto c = static_cast<Eigen::Index>(pos_);
    for (int i = 0; i < obs_dim_; ++i) obs_(i, c) = obs[i], next_obs_(i, c) = next_obs[i];
    for (int i = 0; i < action_dim_; ++i) action_(i, c) = action[i];
    reward_[pos_] = reward;
    done_[pos_] = done ? 1.0 : 0.0;
    if (++pos_ == capacity_) pos_ = 0, full_ = true;
  }

  // batch_size indices uniform in [0, size()), with replacement; throws std::logic_error when empty
  void sample(int batch_size, Rng& rng, ReplayBatch& out) const {
    if (size() == 0) throw std::logic_error("replay buffer: sample from an empty buffer");
    out.obs.resize(obs_dim_, batch_size);
    out.next_obs.resize(obs_dim_, batch_size);
    out.action.resize(action_dim_, batch_size);
    out.reward.resize(batch_size);
    out.done.resize(batch_size);
    for (int j = 0; j < batch_size; ++j) {
      const auto k = static_cast<Eigen::Index>(rng.below(size()));
      out.obs.col(j) = obs_.col(k);
      out.next_obs.col(j) = next_obs_.col(k);
      out.action.col(j) = action_.col(k);
      out.reward[j] = reward_[k];
      out.done[j] = done_[k];
    }
  }

 private:
  std::size_t capacity_;
  int obs_dim_, action_dim_;
  Eigen::MatrixXd obs_, next_obs_, action_;  // one column per transition
  std::vector<double> reward_, done_;
  std::size_t pos_ = 0;
  bool full_ = false;
};

}  // namespace dsb
