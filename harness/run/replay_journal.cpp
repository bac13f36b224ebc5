#include "harness/run/replay_journal.hpp"

#include <stdexcept>
#include <string>

namespace dsb {

void ReplayJournal::serve(std::vector<ReplayEntry> entries, std::int64_t episodes) {
  if (calls_ != 0) throw std::logic_error("set_replay after the run started");
  replay_ = std::move(entries);
  cursor_ = 0;
  replay_episodes_ = episodes;
}

void ReplayJournal::end_serving(bool rl_open) {
  if (replay_.empty()) return;
  // the journal is used up: it must have regenerated exactly the committed episodes, and ended
  // between episodes (it is committed only there)
  if (replayed_episodes_ != replay_episodes_ || rl_open)
    throw ReplayDiverged("resume: the journal regenerated " + std::to_string(replayed_episodes_) +
                         " episodes, the database has " + std::to_string(replay_episodes_));
  replay_.clear();
  replay_.shrink_to_fit();
  journal_first_ = calls_;  // the first live call
}

const ReplayEntry* ReplayJournal::begin_call(ReplayKind kind, std::span<const double> input, bool rl_open) {
  serving_ = false;
  if (cursor_ >= replay_.size()) {
    end_serving(rl_open);
    ++calls_;
    return nullptr;
  }
  const ReplayEntry& e = replay_[cursor_];
  if (e.kind != kind || e.input_hash != replay_input_hash(input))
    throw ReplayDiverged("resume: call " + std::to_string(calls_) + " differs from the journal's");
  ++calls_;
  ++cursor_;
  serving_ = true;
  return &e;
}

void ReplayJournal::write(ReplayKind kind, std::span<const double> input, std::vector<double> payload) {
  if (recording_) journal_.push_back({kind, replay_input_hash(input), std::move(payload)});
}

const ReplayEntry* ReplayJournal::recall(std::uint64_t key, bool rl_open) {
  if (cursor_ >= replay_.size()) {
    end_serving(rl_open);
    return nullptr;  // live: computed, then remembered
  }
  const ReplayEntry& e = replay_[cursor_];
  if (e.kind != ReplayKind::own_work) {
    ++recomputed_work_;  // a journal without own work: computed again, the journal served on
    return nullptr;
  }
  if (e.input_hash != key)
    throw ReplayDiverged("resume: the optimizer's work at call " + std::to_string(calls_) +
                         " differs from the journal's");
  ++calls_;
  ++cursor_;
  ++recalled_work_;
  return &e;
}

void ReplayJournal::remember(std::uint64_t key, std::vector<double> result, bool rl_open) {
  if (cursor_ < replay_.size()) return;  // an older journal is still served: its sequence has no room
  end_serving(rl_open);
  ++calls_;
  if (recording_) journal_.push_back({ReplayKind::own_work, key, std::move(result)});
}

std::vector<ReplayEntry> ReplayJournal::take(std::int64_t& first_seq) {
  first_seq = journal_first_;
  journal_first_ += static_cast<std::int64_t>(journal_.size());
  std::vector<ReplayEntry> out;
  out.swap(journal_);
  return out;
}

}  // namespace dsb
