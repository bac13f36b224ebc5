#include "optimizers/rl/rl_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>

#include "common/error.hpp"
#include "common/field_check.hpp"
#include "common/number_text.hpp"
#include "common/rng.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {

void require_rl_view(const Objective& f, const std::string& optimizer) {
  if (!f.has_rl())
    throw UsageError(optimizer +
                     " needs an env with an RL view (`harness list`, column rl), and this objective has none");
}

std::vector<int> mlp_layer_sizes(int in, const std::vector<int>& hidden, int out) {
  std::vector<int> sizes{in};
  sizes.insert(sizes.end(), hidden.begin(), hidden.end());
  sizes.push_back(out);
  return sizes;
}

void FailedEpisodeLoss::validate(const std::string& owner) const {
  const FieldCheck check(owner);
  check.number_at_least("failed_loss_factor", factor, 1.0);
  check.number_at_least("failed_loss_floor", floor, 0.0);
  check.number_above("failed_loss_before_any", before_any, 0.0);
}

EpisodeLosses::EpisodeLosses(FailedEpisodeLoss failed, std::int64_t block)
    : failed_loss_(failed), block_(std::max<std::int64_t>(block, 1)) {}

double EpisodeLosses::finish_episode(double loss) {
  const auto b = static_cast<std::size_t>(episodes_ / block_);
  if (block_sum_.size() <= b) block_sum_.resize(b + 1, 0.0), block_n_.resize(b + 1, 0);
  ++episodes_;
  if (std::isfinite(loss)) {
    worst_finite_ = any_finite_ ? std::max(worst_finite_, loss) : loss;
    any_finite_ = true;
    block_sum_[b] += loss;
    ++block_n_[b];
    return loss;
  }
  ++failed_;
  if (!any_finite_) return failed_loss_.before_any;
  return std::max(failed_loss_.factor * std::abs(worst_finite_), failed_loss_.floor);
}

void EpisodeLosses::put_diagnostics(nlohmann::json& out) const {
  out["episodes"] = episodes_;
  out["failed_episodes"] = failed_;
  out["loss_block"] = block_;
  std::vector<std::size_t> blocks(block_sum_.size());
  for (std::size_t b = 0; b < blocks.size(); ++b) blocks[b] = b;
  // mean finite episode loss per block (null when every episode of the block failed)
  put_capped(out, "mean_loss_per_block", blocks, [&](std::size_t b, std::size_t) {
    return block_n_[b] > 0 ? nlohmann::json(block_sum_[b] / static_cast<double>(block_n_[b])) : nlohmann::json(nullptr);
  });
}

int sanitize_observation(std::span<double> observation) {
  constexpr double kLimit = 1e6;
  int changed = 0;
  for (double& o : observation) {
    const double c = std::isnan(o) ? 0.0 : std::clamp(o, -kLimit, kLimit);
    if (c != o || std::isnan(o)) o = c, ++changed;
  }
  return changed;
}

std::string params_digest(std::initializer_list<std::span<const double>> parts) {
  std::uint64_t h = fnv1a64(std::string_view());
  for (const auto& p : parts)
    h = fnv1a64(std::string_view(reinterpret_cast<const char*>(p.data()), p.size() * sizeof(double)), h);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

}  // namespace dsb
