#pragma once
// The journal side of a run (harness/core/replay.hpp): it numbers the objective's calls, writes each
// live call's answer to the journal the runner commits, and, for a resumed run, serves the
// committed journal's entries in order until it is used up, checking that it regenerated exactly
// the committed episodes. Knows nothing of envs or episodes' contents.
#include <cstdint>
#include <span>
#include <vector>

#include "harness/core/replay.hpp"

namespace dsb {

class ReplayJournal {
 public:
  // journal live calls (a run with a listener); off: calls are only counted
  void set_recording(bool on) { recording_ = on; }
  bool recording() const { return recording_; }
  // entries to serve before going live, for a run whose first `episodes` episodes they regenerate;
  // before the first call
  void serve(std::vector<ReplayEntry> entries, std::int64_t episodes);

  // Starts a call: the journal's next entry when one is left (it must be for this kind and input,
  // else ReplayDiverged), or null when the call goes live. The first live call checks that the
  // served entries regenerated the committed episodes and that no RL episode is open
  // (`rl_open`), else ReplayDiverged.
  const ReplayEntry* begin_call(ReplayKind kind, std::span<const double> input, bool rl_open);
  // a live call of an RL episode that started live (the journal is already used up)
  void begin_live_call() { ++calls_; }
  bool entries_left() const { return cursor_ < replay_.size(); }
  // whether the call in progress is answered from the journal; the batch path sets it per point
  bool serving() const { return serving_; }
  void set_serving(bool serving) { serving_ = serving; }

  // a live call's answer, journaled when recording
  void write(ReplayKind kind, std::span<const double> input, std::vector<double> payload);

  // The optimizer's own work (ReplayKind::own_work, optimizers/core/work_memo.hpp). recall: the
  // journal's next entry when it is own work under `key` (ReplayDiverged when its key differs),
  // else null: the work is computed, counted as computed again while entries are left (a journal
  // written without own work). remember: a computed result, journaled when recording and live;
  // while an older journal is still served it takes no place in the sequence (not journaled).
  const ReplayEntry* recall(std::uint64_t key, bool rl_open);
  void remember(std::uint64_t key, std::vector<double> result, bool rl_open);
  // own work recalled from the journal, and computed again while it was served
  std::int64_t recalled_work() const { return recalled_work_; }
  std::int64_t recomputed_work() const { return recomputed_work_; }
  // an episode ended (one answered from the journal counts as replayed)
  void episode_finished() {
    if (serving_) ++replayed_episodes_;
  }

  // journal entries since the last take, with the call index of the first
  std::vector<ReplayEntry> take(std::int64_t& first_seq);
  std::int64_t calls() const { return calls_; }
  std::int64_t replayed_episodes() const { return replayed_episodes_; }

 private:
  void end_serving(bool rl_open);

  bool recording_ = false;
  std::int64_t calls_ = 0;          // objective calls so far (the journal's sequence)
  std::int64_t journal_first_ = 0;  // call index of journal_[0]
  std::vector<ReplayEntry> journal_;
  std::vector<ReplayEntry> replay_;  // served from the front
  std::size_t cursor_ = 0;
  std::int64_t replay_episodes_ = 0, replayed_episodes_ = 0;
  std::int64_t recalled_work_ = 0, recomputed_work_ = 0;
  bool serving_ = false;
};

}  // namespace dsb
