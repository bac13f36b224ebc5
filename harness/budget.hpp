#pragma once
// The budget wrapper: the only way an optimizer reaches an env. It checks every point (size, in
// the box, finite), counts and records every episode, keeps the best, turns a blown-up
// simulation into a failed episode, and throws BudgetExhausted once the budget is spent.
// Rollouts reuse workspaces made once per run (one per thread of the run's team); a batch is
// spread over the team, one rollout per thread at a time, and recorded in batch order.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/thread_team.hpp"
#include "envs/core/env.hpp"
#include "harness/replay.hpp"
#include "harness/run_spec.hpp"
#include "optimizers/core/objective.hpp"

namespace dsb {

// Thrown by the budget wrapper when the harness was asked to stop (SIGTERM, SIGINT) after the
// episode in progress: what was done is committed and the run resumes later. It is a
// BudgetExhausted, so optimizers end as they do at the budget; the runner tells them apart by
// BudgetedObjective::interrupted().
struct RunInterrupted : BudgetExhausted {};

// Thrown when a resumed run asks for something other than its journal's next entry (another
// binary, or a bug): the runner then restarts the run from nothing.
struct ReplayDiverged : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class BudgetedObjective;

// What the runner hears after every finished episode: it commits the new evals and journal
// entries when it chooses (every few seconds), and always before an interruption.
class EpisodeListener {
 public:
  virtual ~EpisodeListener() = default;
  virtual void episode_finished(BudgetedObjective& objective, bool commit_now) = 0;
};

class BudgetedObjective : public Objective {
 public:
  // episode_counter (may be null) is incremented after every episode, for progress lines; team
  // (may be null: one thread) runs the threads inside a rollout and the points of a batch
  BudgetedObjective(const Env& env, std::int64_t budget,
                    std::atomic<std::int64_t>* episode_counter = nullptr, ThreadTeam* team = nullptr);

  int dim() const override { return env_.dim(); }
  bool has_gradient() const override { return env_.differentiable(); }
  std::int64_t budget() const override { return budget_; }
  std::int64_t used() const override { return static_cast<std::int64_t>(evals_.size()); }
  double value(std::span<const double> x) override;
  double value_and_grad(std::span<const double> x, std::span<double> grad) override;
  void values(std::span<const double> xs, std::span<double> out) override;
  bool has_rl() const override { return env_.supports_rl(); }
  RlSpec rl_spec() const override;
  void rl_reset(std::span<double> observation) override;
  RlStep rl_step(std::span<const double> action, std::span<double> observation) override;

  const std::vector<EvalRecord>& evals() const { return evals_; }
  double best_loss() const { return best_; }  // NaN while no episode succeeded
  const std::vector<double>& best_x() const { return best_x_; }
  std::int64_t failed_episodes() const { return failed_; }
  // What the objective side saw (the "objective" half of runs.diagnostics): {"episodes",
  // "failed_episodes", "grad_episodes" (episodes with a gradient, failed ones included),
  // "grad_norms": summary of the Euclidean norms of the finite gradients (failed episodes have
  // none) with "zero" (how many were exactly 0)}.
  nlohmann::json diagnostics() const;

  // Journaling and resume (harness/replay.hpp). With a listener, every call is journaled and the
  // listener is told after every episode; `stop` (may be null) is polled after every episode and
  // before every call: once set, the episode is committed and RunInterrupted thrown.
  void set_listener(EpisodeListener* listener, const std::atomic<bool>* stop);
  // entries of a journal to serve before going live, for a run whose first `episodes` evals it
  // regenerates (ReplayDiverged when it does not)
  void set_replay(std::vector<ReplayEntry> entries, std::int64_t episodes);
  // journal entries since the last take, with the call index of the first
  std::vector<ReplayEntry> take_journal(std::int64_t& first_seq);
  std::int64_t replayed_episodes() const { return replayed_episodes_; }
  bool interrupted() const { return interrupted_; }

  // Watches the run's generator for its first draw (checked at the start of every call): the
  // episodes recorded before it, and the calls that produced them, are the run's seed-free
  // prefix (an open RL episode is not part of it)
  void watch_draws(const Rng* rng) { rng_ = rng; }
  // the memory a gradient rollout may keep to spare recomputation (Workspace::tape_memory_bytes);
  // before the first call
  void set_tape_memory(std::size_t bytes) { tape_memory_bytes_ = bytes; }
  SeedFreePrefix seed_free_prefix() const;
  // When a stop was requested: marks the run interrupted and commits what it has, true. For an
  // optimizer that ended with an error the stop caused (an external optimizer killed by it).
  bool stop_if_requested();

 private:
  // the journal's next entry when it answers this call (kind and input digest match), else null;
  // ReplayDiverged when the journal has entries left but they are for another call
  const ReplayEntry* replay_next(ReplayKind kind, std::span<const double> input);
  void end_replay();
  void journal(ReplayKind kind, std::span<const double> input, std::vector<double> payload);
  void check_stop();
  void note_first_draw();
  double finish_episode(double loss_to_return);

  void check_point(std::span<const double> x) const;
  Workspace& workspace(std::size_t slot);
  double record(std::span<const double> x, double loss, bool used_grad, double wall_s, double metric);

  const Env& env_;
  std::int64_t budget_;
  std::atomic<std::int64_t>* counter_;
  ThreadTeam& team_;
  std::vector<std::unique_ptr<Workspace>> workspaces_;  // one per team thread, made on first use
  std::vector<EvalRecord> evals_;
  double best_;
  std::vector<double> best_x_;
  std::int64_t failed_ = 0;
  std::vector<double> grad_norms_;  // |dLoss/dx| of every gradient episode that did not fail
  // RL: the env's per-step view (made on first use), the open episode's start and env steps
  RlEnv& rl_env();
  void write_observation(std::span<double> observation) const;
  std::unique_ptr<RlEnv> rl_;
  bool rl_open_ = false;
  bool rl_served_ = false;  // the open episode is answered from the journal
  std::chrono::steady_clock::time_point rl_start_{};
  // journal and replay
  EpisodeListener* listener_ = nullptr;
  const std::atomic<bool>* stop_ = nullptr;
  bool interrupted_ = false;
  std::int64_t calls_ = 0;           // objective calls so far (journal sequence)
  std::int64_t journal_first_ = 0;   // call index of journal_[0]
  std::vector<ReplayEntry> journal_;
  std::vector<ReplayEntry> replay_;  // served from the front
  std::size_t replay_cursor_ = 0;
  std::int64_t replay_episodes_ = 0, replayed_episodes_ = 0;
  bool serving_ = false;  // the call being recorded was answered from the journal
  // the seed-free prefix
  const Rng* rng_ = nullptr;
  std::size_t tape_memory_bytes_ = 0;
  std::optional<SeedFreePrefix> first_draw_;
  std::int64_t rl_episode_call_ = 0;  // calls before the open RL episode's reset
};

}  // namespace dsb
