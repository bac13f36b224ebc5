#include "harness/run/probe.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <vector>

#include "harness/run/runner.hpp"

namespace dsb {
namespace {

// a grid's run records every episode's replay journal and hands it to the database every
// kCommitIntervalS; a probe does the same, keeping the journal instead of storing it, so that it
// pays what a run pays per episode (on a 10-D synthetic function the journal doubles an
// episode's microseconds) and can then be replayed
class ProbeListener : public EpisodeListener {
 public:
  void episode_finished(BudgetedObjective& objective, bool commit_now) override {
    const auto now = std::chrono::steady_clock::now();
    if (!commit_now && std::chrono::duration<double>(now - last_).count() < kCommitIntervalS) return;
    keep(objective.take_journal(first_seq_));
    last_ = now;
  }
  void keep(std::vector<ReplayEntry> entries) {
    for (auto& e : entries) journal.push_back(std::move(e));
  }
  std::vector<ReplayEntry> journal;

 private:
  std::int64_t first_seq_ = 0;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace

ProbeTiming time_probe(const RunSpec& spec, const Env& env) {
  const std::atomic<bool> stop{false};
  ProbeListener listener;
  RunControl control{&listener, &stop, {}, 0, 0};
  RunResult r = execute_run(spec, env, *spec.new_optimizer(), nullptr, nullptr, &control);
  listener.keep(std::move(r.journal_tail));
  ProbeTiming t{std::max<std::int64_t>(r.episodes, 1), r.wall_s, 0.0, r.wall_s};
  if (r.seed_free.drew && r.seed_free.episodes == 0) return t;
  // the same run from its journal, as a later seed replays the episodes it shares with seed 0 (the
  // plan counts them at this cost, not as free: on a 2-D function replaying an episode costs about
  // what simulating it does)
  ProbeListener again;
  RunControl replay{&again, &stop, std::move(listener.journal), r.episodes, 0};
  const RunResult rr = execute_run(spec, env, *spec.new_optimizer(), nullptr, nullptr, &replay);
  if (rr.replayed_episodes > 0) t.replay_s_per_episode = rr.wall_s / static_cast<double>(rr.replayed_episodes);
  t.total_s += rr.wall_s;
  return t;
}

}  // namespace dsb
