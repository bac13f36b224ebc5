#pragma once
// `sac`: Soft Actor-Critic as Stable-Baselines3's SAC (stable_baselines3/sac/sac.py and
// sac/policies.py) with the seed paper's changes,
// re-implemented on the RL view of the budgeted Objective (Objective::rl_reset / rl_step).
//
// Where this follows SB3 (defaults):
//   - lr 3e-4 for actor, critics and the entropy coefficient, each its own torch-style Adam
//     (eps 1e-8; one Adam over both critics in SB3 is the same, Adam being elementwise);
//   - buffer_size 1e6, learning_starts 100 (uniform random actions while fewer than 100 steps were
//     taken; training after each step once more than 100 were), batch_size 256, tau 0.005,
//     gamma 0.99, train_freq 1 step, gradient_steps 1, target_update_interval 1 (checked on the
//     gradient step's index within one train() call, as SB3 does), 2 critics, no action noise,
//     no gSDE;
//   - ent_coef "auto": log alpha learned from alpha = 1 with target entropy -action_dim, loss
//     -mean(log_alpha (log pi + target_entropy)) with log pi detached;
//   - actor: squashed Gaussian with a state-dependent log-std clamped to [-20, 2] and log pi
//     corrected by -sum log(1 - a^2 + 1e-6); collection samples from it (deterministic = False);
//   - ReLU MLPs with PyTorch's default Linear init, no shared features extractor; the target
//     critics start as copies of the critics;
//   - per gradient step, in SB3's order: one replay batch; a fresh reparameterised actor sample at
//     s; alpha = exp(log_alpha) taken BEFORE the alpha update and used for the rest of the step;
//     the alpha Adam step; the critic target r + (1 - done) gamma (min_k Q'_k(s', a') - alpha log
//     pi(a'|s')) with a' a fresh sample of the current actor at s'; critic loss 0.5 sum_k MSE and
//     its Adam step; actor loss mean(alpha log pi - min_k Q_k(s, a_pi)) on the just-updated critics
//     and its Adam step; Polyak update of the target critics. Random draws in that order: batch
//     indices, the noise at s, the noise at s' (each action_dim x batch, column by column).
// The seed's changes:
//   - net_arch [64, 64, 64] for actor and critics (SB3: [256, 256]);
//   - action repeat is the harness's (one decision here = action_repeat env steps);
//   - fixed horizon, sparse reward: r = 0 on every decision but the last, r = -loss on the last
//     one (the episode's final loss, as recorded by the budget); 1,000 episodes like every method.
// Choices made here (not fixed by SB3 or the seed):
//   - an episode's end is terminal: its last transition is stored with done = 1, so the critic
//     target there is the reward alone. The fixed horizon is not a time limit that cuts a longer
//     task short (SB3's handle_timeout_termination would bootstrap then): the loss at the end is the
//     whole payoff and nothing follows it; `ppo` treats the end the same way;
//   - the terminal reward enters as the reward of the last decision's transition (above);
//   - a failed episode (loss +inf or NaN) is rewarded -max(failed_loss_factor * worst finite loss
//     seen so far in the run, failed_loss_floor), -failed_loss_floor before any finite loss: a
//     large finite penalty so the critics stay finite (the rule: rl_core.hpp, shared with `ppo`);
//   - observation components that are NaN become 0 and all are clamped to [-1e6, 1e6] before the
//     networks or the buffer see them (a blown-up simulation's state would otherwise make every
//     parameter NaN); diagnostics count the changed components ("observations_sanitized");
//   - the replay buffer holds min(buffer_size, remaining budget * decisions) transitions, allocated
//     at the start: memory is bounded by what the run can fill, and the buffer holds the same
//     transitions SB3's would;
//   - randomness only from the run's Rng (initialisation, warm-up actions, batches, noise), all
//     elementary functions deterministic (dm::), no threads: runs are bit-identical per seed.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/rl/rl_core.hpp"
#include "optimizers/rl/sac_update.hpp"

namespace dsb {

struct SacConfig {
  double learning_rate = 3e-4;               // actor, critics, entropy coefficient (SB3)
  double adam_eps = 1e-8;                    // torch default
  std::int64_t buffer_size = 1000000;        // SB3
  int learning_starts = 100;                 // SB3
  int batch_size = 256;                      // SB3
  double tau = 0.005;                        // SB3
  double gamma = 0.99;                       // SB3
  int train_freq = 1;                        // steps between trainings (SB3: 1 step)
  int gradient_steps = 1;                    // per training (SB3)
  int target_update_interval = 1;            // SB3
  int n_critics = 2;                         // SB3
  std::vector<int> net_arch = {64, 64, 64};  // the seed (SB3: [256, 256])
  double ent_coef_init = 1.0;                // SB3 "auto": initial alpha
  double failed_loss_factor = 2.0;           // penalty for a failed episode (chosen here)
  double failed_loss_floor = 1.0;            // ... at least this loss, and this loss before any finite one
  FailedEpisodeLoss failed_loss() const { return {failed_loss_factor, failed_loss_floor, failed_loss_floor}; }
  // throws ConfigError naming the field
  void validate() const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(learning_rate, adam_eps, buffer_size, learning_starts, batch_size, tau, gamma, train_freq,
                    gradient_steps, target_update_interval, n_critics, net_arch, ent_coef_init, failed_loss_factor,
                    failed_loss_floor)
};

std::unique_ptr<Optimizer> make_sac(const SacConfig& cfg = {});

}  // namespace dsb
