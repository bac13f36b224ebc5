#pragma once
// The budget wrapper: the only way an optimizer reaches an env. It answers the optimizer's calls
// (a point, a gradient, a batch, an RL decision) and throws BudgetExhausted once the budget is
// spent. Its jobs live in their own pieces, which it composes:
//  - checks of every request (harness/run/call_checks.hpp),
//  - the record of the episodes and the best (harness/run/episode_log.hpp),
//  - rollouts on the run's team, batches spread over it (harness/run/batch_rollouts.hpp),
//  - the journal and resume by replay (harness/run/replay_journal.hpp),
// and here: the open RL episode, the listener and stop requests, and the seed-free prefix.
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
#include "harness/run/batch_rollouts.hpp"
#include "harness/run/episode_log.hpp"
#include "harness/core/replay.hpp"
#include "harness/run/replay_journal.hpp"
#include "harness/core/run_spec.hpp"
#include "optimizers/core/objective.hpp"

namespace dsb {

// Thrown by the budget wrapper when the harness was asked to stop (SIGTERM, SIGINT) after the
// episode in progress: what was done is committed and the run resumes later. It is a
// BudgetExhausted, so optimizers end as they do at the budget; the runner tells them apart by
// BudgetedObjective::interrupted().
struct RunInterrupted : BudgetExhausted {};

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
  BudgetedObjective(const Env& env, std::int64_t budget, std::atomic<std::int64_t>* episode_counter = nullptr,
                    ThreadTeam* team = nullptr);

  int dim() const override { return env_.dim(); }
  bool has_gradient() const override { return env_.differentiable(); }
  std::int64_t budget() const override { return budget_; }
  std::int64_t used() const override { return log_.episodes(); }
  double value(std::span<const double> x) override;
  double value_and_grad(std::span<const double> x, std::span<double> grad) override;
  void values(std::span<const double> xs, std::span<double> out) override;
  bool has_rl() const override { return env_.supports_rl(); }
  RlSpec rl_spec() const override;
  void rl_reset(std::span<double> observation) override;
  RlStep rl_step(std::span<const double> action, std::span<double> observation) override;
  // the optimizer's own work, kept in the journal (ReplayJournal::recall, remember); a recalled
  // result of another size than `out` is ReplayDiverged
  bool recall(std::uint64_t key, std::span<double> out) override;
  void remember(std::uint64_t key, std::span<const double> result) override;

  const std::vector<EvalRecord>& evals() const { return log_.evals(); }
  double best_loss() const { return log_.best_loss(); }  // NaN while no episode succeeded
  const std::vector<double>& best_x() const { return log_.best_x(); }
  std::int64_t failed_episodes() const { return log_.failed_episodes(); }
  // What the objective side saw (the "objective" half of runs.diagnostics; EpisodeLog::diagnostics)
  nlohmann::json diagnostics() const { return log_.diagnostics(); }

  // Journaling and resume (harness/core/replay.hpp). With a listener, every call is journaled and the
  // listener is told after every episode; `stop` (may be null) is polled after every episode and
  // before every call: once set, the episode is committed and RunInterrupted thrown.
  void set_listener(EpisodeListener* listener, const std::atomic<bool>* stop);
  // entries of a journal to serve before going live, for a run whose first `episodes` evals it
  // regenerates (ReplayDiverged when it does not)
  void set_replay(std::vector<ReplayEntry> entries, std::int64_t episodes);
  // journal entries since the last take, with the call index of the first
  std::vector<ReplayEntry> take_journal(std::int64_t& first_seq) { return journal_.take(first_seq); }
  std::int64_t replayed_episodes() const { return journal_.replayed_episodes(); }
  // results of the optimizer's own work recalled from the journal, and computed again while it
  // was served (a journal written without them)
  std::int64_t recalled_work() const { return journal_.recalled_work(); }
  std::int64_t recomputed_work() const { return journal_.recomputed_work(); }
  bool interrupted() const { return interrupted_; }

  // Watches the run's generator for its first draw (checked at the start of every call): the
  // episodes recorded before it, and the calls that produced them, are the run's seed-free
  // prefix (an open RL episode is not part of it)
  void watch_draws(const Rng* rng) { rng_ = rng; }
  // the memory a gradient rollout may keep to spare recomputation (Workspace::tape_memory_bytes);
  // before the first call
  void set_tape_memory(std::size_t bytes) { workspaces_.set_tape_memory(bytes); }
  SeedFreePrefix seed_free_prefix() const;
  // When a stop was requested: marks the run interrupted and commits what it has, true. For an
  // optimizer that ended with an error the stop caused (an external optimizer killed by it).
  bool stop_if_requested();

 private:
  void note_first_draw();
  // before every call: the stop request, then the budget
  void begin_call();
  // the episode is over: recorded, the listener told, a requested stop obeyed
  double finish_episode(std::span<const double> x, double loss, bool used_grad, double wall_s, double metric);

  // RL: the env's per-step view (made on first use) and the open episode
  RlEnv& rl_env();
  void write_observation(std::span<double> observation) const;
  struct RlEpisode {
    bool open = false;
    bool served = false;  // answered from the journal, to its end
    std::chrono::steady_clock::time_point start{};
    std::int64_t first_call = 0;  // calls before its reset
  };

  const Env& env_;
  std::int64_t budget_;
  ThreadTeam& team_;
  WorkspacePool workspaces_;  // one per team thread
  EpisodeLog log_;
  ReplayJournal journal_;
  std::unique_ptr<RlEnv> rl_;
  RlEpisode rl_episode_;
  EpisodeListener* listener_ = nullptr;
  const std::atomic<bool>* stop_ = nullptr;
  bool interrupted_ = false;
  // the seed-free prefix
  const Rng* rng_ = nullptr;
  std::optional<SeedFreePrefix> first_draw_;
};

}  // namespace dsb
