#include "harness/run/budget.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/parallel.hpp"
#include "harness/run/call_checks.hpp"

namespace dsb {

BudgetedObjective::BudgetedObjective(const Env& env, std::int64_t budget, std::atomic<std::int64_t>* episode_counter,
                                     ThreadTeam* team)
    : env_(env),
      budget_(budget),
      team_(team ? *team : serial_team()),
      workspaces_(env, team_.size()),
      log_(budget, episode_counter) {}

double BudgetedObjective::finish_episode(std::span<const double> x, double loss, bool used_grad, double wall_s,
                                         double metric) {
  const double seen = log_.add(x, loss, used_grad, wall_s, metric);
  journal_.episode_finished();
  // the episode is over: the listener may commit it; a requested stop commits and ends the run
  const bool stop = stop_ && stop_->load(std::memory_order_relaxed);
  if (listener_) listener_->episode_finished(*this, stop);
  if (stop) {
    interrupted_ = true;
    throw RunInterrupted{};
  }
  return seen;
}

void BudgetedObjective::set_listener(EpisodeListener* listener, const std::atomic<bool>* stop) {
  listener_ = listener;
  stop_ = stop;
  journal_.set_recording(listener != nullptr);
}

void BudgetedObjective::set_replay(std::vector<ReplayEntry> entries, std::int64_t episodes) {
  journal_.serve(std::move(entries), episodes);
}

void BudgetedObjective::note_first_draw() {
  if (!rng_ || first_draw_ || rng_->draws() == 0) return;
  // a draw since the last call: what was recorded before it is seed-free (an open RL episode's
  // decisions came after it)
  first_draw_ = SeedFreePrefix{used(), rl_episode_.open ? rl_episode_.first_call : journal_.calls(), true};
}

SeedFreePrefix BudgetedObjective::seed_free_prefix() const {
  return first_draw_ ? *first_draw_
                     : SeedFreePrefix{used(), rl_episode_.open ? rl_episode_.first_call : journal_.calls(), false};
}

bool BudgetedObjective::stop_if_requested() {
  if (interrupted_) return true;
  if (!stop_ || !stop_->load(std::memory_order_relaxed)) return false;
  interrupted_ = true;
  if (listener_) listener_->episode_finished(*this, true);
  return true;
}

void BudgetedObjective::begin_call() {
  if (stop_if_requested()) throw RunInterrupted{};
  if (used() >= budget_) throw BudgetExhausted{};
}

double BudgetedObjective::value(std::span<const double> x) {
  note_first_draw();
  begin_call();
  check_point(env_, x);
  if (const ReplayEntry* r = journal_.begin_call(ReplayKind::value, x, rl_episode_.open)) {
    const auto a = EpisodeAnswer::from(*r, 0);
    return finish_episode(x, a.loss, false, a.wall_s, a.metric);
  }
  const auto start = std::chrono::steady_clock::now();
  Workspace& ws = workspaces_.get(0);
  EpisodeAnswer a;
  a.loss = env_.loss(x, ws, team_);
  a.wall_s = seconds_since(start);
  a.metric = env_.episode_metric(ws);
  journal_.write(ReplayKind::value, x, a.payload());
  return finish_episode(x, a.loss, false, a.wall_s, a.metric);
}

double BudgetedObjective::value_and_grad(std::span<const double> x, std::span<double> grad) {
  note_first_draw();
  begin_call();
  check_point(env_, x);
  check_gradient_buffer(env_, grad);
  double loss = 0.0, wall_s = 0.0, metric = 0.0;
  if (const ReplayEntry* r = journal_.begin_call(ReplayKind::value_and_grad, x, rl_episode_.open)) {
    const auto a = EpisodeAnswer::from(*r, grad.size());
    loss = a.loss;
    metric = a.metric;
    wall_s = a.wall_s;
    std::copy(a.gradient.begin(), a.gradient.end(), grad.begin());
  } else {
    const auto start = std::chrono::steady_clock::now();
    Workspace& ws = workspaces_.get(0);
    loss = env_.loss_and_grad(x, grad, ws, team_);
    wall_s = seconds_since(start);
    metric = env_.episode_metric(ws);
    if (journal_.recording())
      journal_.write(ReplayKind::value_and_grad, x,
                     EpisodeAnswer{loss, metric, wall_s, {grad.begin(), grad.end()}}.payload());
  }
  bool finite = std::isfinite(loss);
  for (double g : grad) finite = finite && std::isfinite(g);
  // a failed episode's gradient reaches the optimizer as zeros and is left out of the norms
  if (!finite) std::fill(grad.begin(), grad.end(), 0.0);
  if (finite) log_.add_gradient(grad);
  return finish_episode(x, finite ? loss : std::numeric_limits<double>::quiet_NaN(), true, wall_s, metric);
}

void BudgetedObjective::values(std::span<const double> xs, std::span<double> out) {
  const std::size_t d = static_cast<std::size_t>(env_.dim());
  check_batch(xs.size(), out.size(), d);
  if (out.empty()) return;
  note_first_draw();
  begin_call();
  auto point = [&](std::size_t i) { return xs.subspan(i * d, d); };
  // what one-at-a-time evaluation would reach: the points before the first bad one, within budget
  std::size_t n = std::min<std::size_t>(out.size(), static_cast<std::size_t>(budget_ - used()));
  std::exception_ptr bad_point;
  for (std::size_t i = 0; i < n; ++i) {
    try {
      check_point(env_, point(i));
    } catch (...) {
      bad_point = std::current_exception();
      n = i;
      break;
    }
  }
  std::vector<RolloutOutcome> outcomes(n);
  // a resumed run serves the batch's first points from its journal (in order), simulates the rest
  std::size_t n_served = 0;
  while (n_served < n && journal_.entries_left()) {
    const auto a = EpisodeAnswer::from(*journal_.begin_call(ReplayKind::value, point(n_served), rl_episode_.open), 0);
    outcomes[n_served] = {a.loss, a.wall_s, a.metric, nullptr};
    ++n_served;
  }
  std::vector<std::size_t> live;
  for (std::size_t i = n_served; i < n; ++i) live.push_back(i);
  run_value_batch(env_, team_, workspaces_, xs, d, live, outcomes);
  for (std::size_t i = 0; i < n; ++i) {
    if (outcomes[i].error) std::rethrow_exception(outcomes[i].error);
    const RolloutOutcome& o = outcomes[i];
    if (i < n_served) {
      journal_.set_serving(true);
    } else {
      // the journal is used up: the first live point checks and closes it
      journal_.begin_call(ReplayKind::value, point(i), rl_episode_.open);
      journal_.write(ReplayKind::value, point(i), EpisodeAnswer{o.loss, o.metric, o.wall_s, {}}.payload());
    }
    out[i] = finish_episode(point(i), o.loss, false, o.wall_s, o.metric);
  }
  journal_.set_serving(false);
  if (bad_point) std::rethrow_exception(bad_point);
  if (n < out.size()) throw BudgetExhausted{};
}

bool BudgetedObjective::recall(std::uint64_t key, std::span<double> out) {
  note_first_draw();  // work that drew belongs after the seed-free prefix
  const ReplayEntry* e = journal_.recall(key, rl_episode_.open);
  if (!e) return false;
  if (e->payload.size() != out.size())
    throw ReplayDiverged("resume: a journal result of the optimizer's work of " + std::to_string(e->payload.size()) +
                         " values, expected " + std::to_string(out.size()));
  std::copy(e->payload.begin(), e->payload.end(), out.begin());
  return true;
}

void BudgetedObjective::remember(std::uint64_t key, std::span<const double> result) {
  note_first_draw();
  journal_.remember(key, {result.begin(), result.end()}, rl_episode_.open);
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
  if (rl_episode_.open) throw std::logic_error("rl_reset while an episode is open: finish it first (it is recorded)");
  note_first_draw();
  begin_call();  // between episodes only: an open episode always runs to its end
  rl_episode_.first_call = journal_.calls();
  if (const ReplayEntry* r = journal_.begin_call(ReplayKind::rl_reset, {}, rl_episode_.open)) {
    // the payload is the observation
    if (r->payload.size() != observation.size())
      throw ReplayDiverged("resume: a journal observation of the wrong size");
    std::copy(r->payload.begin(), r->payload.end(), observation.begin());
    rl_episode_.open = true;
    rl_episode_.served = true;
    return;
  }
  rl.reset();
  rl_episode_.open = true;
  rl_episode_.served = false;
  rl_episode_.start = std::chrono::steady_clock::now();
  write_observation(observation);
  journal_.write(ReplayKind::rl_reset, {}, std::vector<double>(observation.begin(), observation.end()));
}

RlStep BudgetedObjective::rl_step(std::span<const double> action, std::span<double> observation) {
  RlEnv& rl = rl_env();
  if (!rl_episode_.open) throw std::logic_error("rl_step without an open episode (call rl_reset first)");
  note_first_draw();
  check_action(env_, rl.action_dim(), action);
  if (rl_episode_.served) {
    // an episode of the journal: its decisions are answered from it, to its end
    if (!journal_.entries_left()) throw ReplayDiverged("resume: the journal ends inside an RL episode");
    const auto a =
        RlStepAnswer::from(*journal_.begin_call(ReplayKind::rl_step, action, rl_episode_.open), observation.size());
    std::copy(a.observation.begin(), a.observation.end(), observation.begin());
    if (!a.done) return {false, 0.0};
    rl_episode_ = {};
    return {true, finish_episode({}, a.loss, false, a.wall_s, a.metric)};
  }
  journal_.begin_live_call();
  // one decision: the action held for action_repeat env steps, or until the episode ends
  for (int k = 0; k < rl.action_repeat() && !rl.done(); ++k) rl.step(action);
  write_observation(observation);
  // a simulation that blew up (a non-finite observation) ends its episode as a failed one: the
  // optimizer never sees NaN, and nothing after the blow-up is simulated
  bool blown_up = false;
  for (const double o : observation) blown_up = blown_up || !std::isfinite(o);
  if (blown_up) std::fill(observation.begin(), observation.end(), 0.0);
  RlStepAnswer a;
  a.done = rl.done() || blown_up;
  a.loss = !a.done ? 0.0 : blown_up ? std::numeric_limits<double>::quiet_NaN() : rl.final_loss();
  a.wall_s = a.done ? seconds_since(rl_episode_.start) : 0.0;
  if (a.done && !blown_up) a.metric = rl.final_metric();
  if (journal_.recording()) {
    a.observation.assign(observation.begin(), observation.end());
    journal_.write(ReplayKind::rl_step, action, a.payload());
  }
  if (!a.done) return {false, 0.0};
  rl_episode_ = {};
  return {true, finish_episode({}, a.loss, false, a.wall_s, a.metric)};
}

}  // namespace dsb
