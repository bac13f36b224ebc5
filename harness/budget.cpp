#include "harness/budget.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/number_text.hpp"
#include "common/parallel.hpp"
#include "common/unit_box.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

BudgetedObjective::BudgetedObjective(const Env& env, std::int64_t budget,
                                     std::atomic<std::int64_t>* episode_counter, ThreadTeam* team)
    : env_(env), budget_(budget), counter_(episode_counter), team_(team ? *team : serial_team()),
      workspaces_(static_cast<std::size_t>(team_.size())), best_(std::numeric_limits<double>::quiet_NaN()) {
  evals_.reserve(static_cast<std::size_t>(budget));
}

Workspace& BudgetedObjective::workspace(std::size_t slot) {
  if (!workspaces_[slot]) {
    workspaces_[slot] = env_.make_workspace();
    // gradient rollouts use slot 0 only: it gets the run's tape memory
    if (slot == 0) workspaces_[slot]->tape_memory_bytes = tape_memory_bytes_;
  }
  return *workspaces_[slot];
}

void BudgetedObjective::check_point(std::span<const double> x) const {
  if (static_cast<int>(x.size()) != env_.dim())
    throw std::logic_error("optimizer asked for a point of dimension " + std::to_string(x.size()) +
                           " on env '" + env_.name() + "' of dimension " + std::to_string(env_.dim()));
  if (const auto i = first_outside_box(x); i >= 0)
    throw std::logic_error("optimizer asked for x[" + std::to_string(i) + "] = " + number_text(x[i]) +
                           " outside [-1, 1]");
}

double BudgetedObjective::record(std::span<const double> x, double loss, bool used_grad, double wall_s,
                                 double metric) {
  const bool failed = !std::isfinite(loss);
  if (failed) {
    loss = std::numeric_limits<double>::quiet_NaN();
    ++failed_;
  } else if (std::isnan(best_) || loss < best_) {
    best_ = loss;
    best_x_.assign(x.begin(), x.end());
  }
  evals_.push_back({static_cast<std::int64_t>(evals_.size()), loss, best_, used_grad, wall_s,
                    failed ? std::numeric_limits<double>::quiet_NaN() : metric});
  if (counter_) counter_->fetch_add(1, std::memory_order_relaxed);
  if (serving_) ++replayed_episodes_;
  // the episode is over: the listener may commit it; a requested stop commits and ends the run
  const bool stop = stop_ && stop_->load(std::memory_order_relaxed);
  if (listener_) listener_->episode_finished(*this, stop);
  if (stop) {
    interrupted_ = true;
    throw RunInterrupted{};
  }
  return failed ? std::numeric_limits<double>::infinity() : loss;
}

void BudgetedObjective::set_listener(EpisodeListener* listener, const std::atomic<bool>* stop) {
  listener_ = listener;
  stop_ = stop;
}

void BudgetedObjective::set_replay(std::vector<ReplayEntry> entries, std::int64_t episodes) {
  if (calls_ != 0) throw std::logic_error("set_replay after the run started");
  replay_ = std::move(entries);
  replay_cursor_ = 0;
  replay_episodes_ = episodes;
}

std::vector<ReplayEntry> BudgetedObjective::take_journal(std::int64_t& first_seq) {
  first_seq = journal_first_;
  journal_first_ += static_cast<std::int64_t>(journal_.size());
  std::vector<ReplayEntry> out;
  out.swap(journal_);
  return out;
}

void BudgetedObjective::note_first_draw() {
  if (!rng_ || first_draw_ || rng_->draws() == 0) return;
  // a draw since the last call: what was recorded before it is seed-free (an open RL episode's
  // decisions came after it)
  first_draw_ = SeedFreePrefix{used(), rl_open_ ? rl_episode_call_ : calls_, true};
}

SeedFreePrefix BudgetedObjective::seed_free_prefix() const {
  return first_draw_ ? *first_draw_ : SeedFreePrefix{used(), rl_open_ ? rl_episode_call_ : calls_, false};
}

bool BudgetedObjective::stop_if_requested() {
  if (interrupted_) return true;
  if (!stop_ || !stop_->load(std::memory_order_relaxed)) return false;
  interrupted_ = true;
  if (listener_) listener_->episode_finished(*this, true);
  return true;
}

void BudgetedObjective::check_stop() {
  if (stop_if_requested()) throw RunInterrupted{};
}

void BudgetedObjective::end_replay() {
  if (replay_.empty()) return;
  // the journal is used up: it must have regenerated exactly the committed episodes, and ended
  // between episodes (it is committed only there)
  if (replayed_episodes_ != replay_episodes_ || rl_open_)
    throw ReplayDiverged("resume: the journal regenerated " + std::to_string(replayed_episodes_) +
                         " episodes, the database has " + std::to_string(replay_episodes_));
  replay_.clear();
  replay_.shrink_to_fit();
  journal_first_ = calls_;  // the first live call
}

const ReplayEntry* BudgetedObjective::replay_next(ReplayKind kind, std::span<const double> input) {
  serving_ = false;
  if (replay_cursor_ >= replay_.size()) {
    end_replay();
    ++calls_;
    return nullptr;
  }
  const ReplayEntry& e = replay_[replay_cursor_];
  if (e.kind != kind || e.input_hash != replay_input_hash(input))
    throw ReplayDiverged("resume: call " + std::to_string(calls_) + " differs from the journal's");
  ++calls_;
  ++replay_cursor_;
  serving_ = true;
  return &e;
}

void BudgetedObjective::journal(ReplayKind kind, std::span<const double> input, std::vector<double> payload) {
  if (listener_) journal_.push_back({kind, replay_input_hash(input), std::move(payload)});
}

double BudgetedObjective::value(std::span<const double> x) {
  note_first_draw();
  check_stop();
  if (used() >= budget_) throw BudgetExhausted{};
  check_point(x);
  if (const ReplayEntry* r = replay_next(ReplayKind::value, x))
    return record(x, r->payload.at(0), false, r->payload.at(2), r->payload.at(1));
  const auto start = std::chrono::steady_clock::now();
  const double loss = env_.loss(x, workspace(0), team_);
  const double wall_s = seconds_since(start), metric = env_.episode_metric(workspace(0));
  journal(ReplayKind::value, x, {loss, metric, wall_s});
  return record(x, loss, false, wall_s, metric);
}

double BudgetedObjective::value_and_grad(std::span<const double> x, std::span<double> grad) {
  note_first_draw();
  check_stop();
  if (used() >= budget_) throw BudgetExhausted{};
  check_point(x);
  if (static_cast<int>(grad.size()) != env_.dim())
    throw std::logic_error("gradient buffer has the wrong size");
  double loss = 0.0, wall_s = 0.0, metric = 0.0;
  if (const ReplayEntry* r = replay_next(ReplayKind::value_and_grad, x)) {
    if (r->payload.size() != 3 + grad.size()) throw ReplayDiverged("resume: a journal gradient of the wrong size");
    loss = r->payload[0];
    metric = r->payload[1];
    wall_s = r->payload[2];
    std::copy(r->payload.begin() + 3, r->payload.end(), grad.begin());
  } else {
    const auto start = std::chrono::steady_clock::now();
    loss = env_.loss_and_grad(x, grad, workspace(0), team_);
    wall_s = seconds_since(start);
    metric = env_.episode_metric(workspace(0));
    if (listener_) {
      std::vector<double> payload = {loss, metric, wall_s};
      payload.insert(payload.end(), grad.begin(), grad.end());
      journal(ReplayKind::value_and_grad, x, std::move(payload));
    }
  }
  bool finite = std::isfinite(loss);
  for (double g : grad) finite = finite && std::isfinite(g);
  if (!finite) std::fill(grad.begin(), grad.end(), 0.0);
  // |g| = sqrt(sum g_i^2), summed in index order
  if (finite) {
    double sq = 0.0;
    for (double g : grad) sq += g * g;
    grad_norms_.push_back(std::sqrt(sq));
  }
  return record(x, finite ? loss : std::numeric_limits<double>::quiet_NaN(), true, wall_s, metric);
}

void BudgetedObjective::values(std::span<const double> xs, std::span<double> out) {
  const std::size_t d = static_cast<std::size_t>(env_.dim());
  if (xs.size() != out.size() * d)
    throw std::logic_error("batch of " + std::to_string(out.size()) + " points has " +
                           std::to_string(xs.size()) + " values, expected " + std::to_string(out.size() * d));
  if (out.empty()) return;
  note_first_draw();
  check_stop();
  if (used() >= budget_) throw BudgetExhausted{};
  auto point = [&](std::size_t i) { return xs.subspan(i * d, d); };
  // what one-at-a-time evaluation would reach: the points before the first bad one, within budget
  std::size_t n = std::min<std::size_t>(out.size(), static_cast<std::size_t>(budget_ - used()));
  std::exception_ptr bad_point;
  for (std::size_t i = 0; i < n; ++i) {
    try {
      check_point(point(i));
    } catch (...) {
      bad_point = std::current_exception();
      n = i;
      break;
    }
  }
  // each slot takes every slots-th point with its own workspace, serially inside the rollout
  // (a nested parallel loop of the env runs on the slot's thread): results do not depend on the slot
  struct Outcome {
    double loss = 0.0, wall_s = 0.0, metric = 0.0;
    std::exception_ptr error;
    bool served = false;
  };
  std::vector<Outcome> outcomes(n);
  // a resumed run serves the batch's first points from its journal (in order), simulates the rest
  std::size_t n_served = 0;
  while (n_served < n && replay_cursor_ < replay_.size()) {
    const ReplayEntry* r = replay_next(ReplayKind::value, point(n_served));
    outcomes[n_served] = {r->payload.at(0), r->payload.at(2), r->payload.at(1), nullptr, true};
    ++n_served;
  }
  std::vector<std::size_t> live;
  for (std::size_t i = n_served; i < n; ++i) live.push_back(i);
  const std::size_t slots = std::min<std::size_t>(live.size(), static_cast<std::size_t>(team_.size()));
  for (std::size_t s = 0; s < slots; ++s) workspace(s);
  team_.run(static_cast<int>(slots), [&](int slot) {
    for (std::size_t k = static_cast<std::size_t>(slot); k < live.size(); k += slots) {
      const std::size_t i = live[k];
      const auto start = std::chrono::steady_clock::now();
      try {
        outcomes[i].loss = env_.loss(point(i), *workspaces_[slot], team_);
        outcomes[i].metric = env_.episode_metric(*workspaces_[slot]);
      } catch (...) {
        outcomes[i].error = std::current_exception();
      }
      outcomes[i].wall_s = seconds_since(start);
    }
  });
  for (std::size_t i = 0; i < n; ++i) {
    if (outcomes[i].error) std::rethrow_exception(outcomes[i].error);
    serving_ = outcomes[i].served;
    if (!serving_) {
      end_replay();  // the first live point checks and closes a journal that ended in this batch
      ++calls_;
      journal(ReplayKind::value, point(i), {outcomes[i].loss, outcomes[i].metric, outcomes[i].wall_s});
    }
    out[i] = record(point(i), outcomes[i].loss, false, outcomes[i].wall_s, outcomes[i].metric);
  }
  serving_ = false;
  if (bad_point) std::rethrow_exception(bad_point);
  if (n < out.size()) throw BudgetExhausted{};
}

RlEnv& BudgetedObjective::rl_env() {
  if (!env_.supports_rl()) throw std::logic_error("env '" + env_.name() + "' has no RL view");
  if (!rl_) rl_ = env_.make_rl();
  return *rl_;
}

RlSpec BudgetedObjective::rl_spec() const {
  auto& self = const_cast<BudgetedObjective&>(*this);  // the view is made on first use
  const RlEnv& rl = self.rl_env();
  const int repeat = rl.action_repeat();
  return {rl.observation_dim(), rl.action_dim(), repeat, (rl.horizon() + repeat - 1) / repeat};
}

void BudgetedObjective::write_observation(std::span<double> observation) const {
  const std::vector<double> o = rl_->observe();
  if (observation.size() != o.size())
    throw std::logic_error("observation buffer has " + std::to_string(observation.size()) + " values, the env " +
                           std::to_string(o.size()));
  std::copy(o.begin(), o.end(), observation.begin());
}

void BudgetedObjective::rl_reset(std::span<double> observation) {
  RlEnv& rl = rl_env();
  if (rl_open_) throw std::logic_error("rl_reset while an episode is open: finish it first (it is recorded)");
  note_first_draw();
  check_stop();  // between episodes only: an open episode always runs to its end
  if (used() >= budget_) throw BudgetExhausted{};
  rl_episode_call_ = calls_;
  if (const ReplayEntry* r = replay_next(ReplayKind::rl_reset, {})) {
    if (r->payload.size() != observation.size()) throw ReplayDiverged("resume: a journal observation of the wrong size");
    std::copy(r->payload.begin(), r->payload.end(), observation.begin());
    rl_open_ = true;
    rl_served_ = true;
    return;
  }
  rl.reset();
  rl_open_ = true;
  rl_served_ = false;
  rl_start_ = std::chrono::steady_clock::now();
  write_observation(observation);
  journal(ReplayKind::rl_reset, {}, std::vector<double>(observation.begin(), observation.end()));
}

RlStep BudgetedObjective::rl_step(std::span<const double> action, std::span<double> observation) {
  RlEnv& rl = rl_env();
  if (!rl_open_) throw std::logic_error("rl_step without an open episode (call rl_reset first)");
  note_first_draw();
  if (static_cast<int>(action.size()) != rl.action_dim())
    throw std::logic_error("optimizer gave an action of size " + std::to_string(action.size()) + " on env '" +
                           env_.name() + "' with " + std::to_string(rl.action_dim()) + " actions");
  for (std::size_t i = 0; i < action.size(); ++i)
    if (!(action[i] >= -1.0 && action[i] <= 1.0))
      throw std::logic_error("optimizer gave action[" + std::to_string(i) + "] = " + std::to_string(action[i]) +
                             " outside [-1, 1]");
  if (rl_served_) {
    // an episode of the journal: its decisions are answered from it, to its end
    const ReplayEntry* r = replay_cursor_ < replay_.size() ? replay_next(ReplayKind::rl_step, action) : nullptr;
    if (!r || r->payload.size() != 3 + observation.size())
      throw ReplayDiverged("resume: the journal ends inside an RL episode");
    std::copy(r->payload.begin() + 3, r->payload.end(), observation.begin());
    if (r->payload[0] == 0.0) return {false, 0.0};
    rl_open_ = false;
    rl_served_ = false;
    const double loss = record({}, r->payload[1], false, r->payload[2], std::numeric_limits<double>::quiet_NaN());
    return {true, loss};
  }
  ++calls_;
  // one decision: the action held for action_repeat env steps, or until the episode ends
  for (int k = 0; k < rl.action_repeat() && !rl.done(); ++k) rl.step(action);
  write_observation(observation);
  // a simulation that blew up (a non-finite observation) ends its episode as a failed one: the
  // optimizer never sees NaN, and nothing after the blow-up is simulated
  bool blown_up = false;
  for (const double o : observation) blown_up = blown_up || !std::isfinite(o);
  if (blown_up) std::fill(observation.begin(), observation.end(), 0.0);
  const bool done = rl.done() || blown_up;
  const double raw_loss = !done ? 0.0 : blown_up ? std::numeric_limits<double>::quiet_NaN() : rl.final_loss();
  const double wall_s = done ? seconds_since(rl_start_) : 0.0;
  if (listener_) {
    std::vector<double> payload = {done ? 1.0 : 0.0, raw_loss, wall_s};
    payload.insert(payload.end(), observation.begin(), observation.end());
    journal(ReplayKind::rl_step, action, std::move(payload));
  }
  if (!done) return {false, 0.0};
  rl_open_ = false;
  const double loss = record({}, raw_loss, false, wall_s, std::numeric_limits<double>::quiet_NaN());
  return {true, loss};
}

nlohmann::json BudgetedObjective::diagnostics() const {
  std::int64_t grad_episodes = 0;
  for (const auto& e : evals_) grad_episodes += e.used_grad ? 1 : 0;
  std::int64_t zero = 0;
  for (double g : grad_norms_) zero += g == 0.0 ? 1 : 0;
  nlohmann::json norms = summarize(grad_norms_);
  norms["zero"] = zero;
  return {{"episodes", used()},
          {"failed_episodes", failed_},
          {"grad_episodes", grad_episodes},
          {"grad_norms", std::move(norms)}};
}

}  // namespace dsb
