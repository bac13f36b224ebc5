#include "harness/run/runner.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

#include "common/thread_cpu_clock.hpp"
#include "harness/run/budget.hpp"
#include "harness/run/fault_injection.hpp"
#include "harness/run/interrupt.hpp"
#include "harness/run/progress.hpp"

namespace dsb {

RunResult execute_run(const RunSpec& spec, const Env& env, Optimizer& optimizer,
                      std::atomic<std::int64_t>* episode_counter, ThreadTeam* team, RunControl* control) {
  RunResult result;
  const auto start = std::chrono::steady_clock::now();
  BudgetedObjective objective(env, spec.budget, episode_counter, team);
  if (control) {
    objective.set_tape_memory(control->tape_memory_bytes);
    objective.set_listener(control->listener, control->stop);
    objective.set_replay(std::move(control->journal), control->journal_episodes);
  }
  Rng rng(spec.rng_seed);
  objective.watch_draws(&rng);
  result.status = RunStatus::done;
  try {
    optimizer.minimize(objective, rng);
  } catch (const BudgetExhausted&) {
    // the normal end: the budget is spent (or a stop request, below)
  } catch (const ReplayDiverged& e) {
    result.status = RunStatus::diverged;
    result.error = e.what();
  } catch (const std::exception& e) {
    result.status = RunStatus::failed;
    result.error = e.what();
    // an error after a stop request is the stop's doing (an external optimizer killed by it):
    // the run commits and resumes like any other
    if (objective.stop_if_requested()) result.error.clear();
  }
  // an optimizer may catch a stop like the budget's end and return: the objective knows
  if (objective.interrupted()) result.status = RunStatus::interrupted;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.episodes = objective.used();
  result.failed_episodes = objective.failed_episodes();
  result.best_loss = objective.best_loss();
  result.best_x = objective.best_x();
  result.evals = objective.evals();
  result.diagnostics = {{"optimizer", optimizer.diagnostics()}, {"objective", objective.diagnostics()}};
  result.replayed_episodes = objective.replayed_episodes();
  result.recalled_work = objective.recalled_work();
  result.recomputed_work = objective.recomputed_work();
  result.seed_free = objective.seed_free_prefix();
  if (control) result.journal_tail = objective.take_journal(result.journal_tail_first_seq);
  return result;
}

namespace {

// commits a running run's new episodes and journal every kCommitIntervalS, and at once when asked,
// with the CPU seconds the run has spent so far (`cpu_s`)
class CommitListener : public EpisodeListener {
 public:
  CommitListener(Store& store, std::int64_t run_id, std::int64_t committed, std::function<double()> cpu_s)
      : store_(store),
        run_id_(run_id),
        committed_(committed),
        cpu_s_(std::move(cpu_s)),
        last_(std::chrono::steady_clock::now()) {}

  void episode_finished(BudgetedObjective& objective, bool commit_now) override {
    const auto now = std::chrono::steady_clock::now();
    const int fault = fault_signal_in_run(objective.used());
    commit_now = commit_now || fault != 0 || fault_commit_every_episode();
    if (!commit_now && std::chrono::duration<double>(now - last_).count() < kCommitIntervalS) return;
    const auto& evals = objective.evals();
    const auto first = static_cast<std::size_t>(std::min<std::int64_t>(committed_, evals.size()));
    std::int64_t first_seq = 0;
    const std::vector<ReplayEntry> journal = objective.take_journal(first_seq);
    store_.append_progress(run_id_, std::span<const EvalRecord>(evals).subspan(first), first_seq, journal,
                           objective.seed_free_prefix(), cpu_s_());
    committed_ = static_cast<std::int64_t>(evals.size());
    last_ = now;
    if (fault != 0) fault_raise(fault);
  }

 private:
  Store& store_;
  std::int64_t run_id_, committed_;
  std::function<double()> cpu_s_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace

GridSummary run_grid(const std::vector<PlannedRun>& pending, const std::vector<double>& run_cost_s,
                     const std::vector<std::ptrdiff_t>& leads, std::int64_t skipped, Store& store, int jobs,
                     int threads, std::FILE* progress_out, const std::function<void()>& on_run_finished, bool share,
                     std::size_t tape_memory_bytes) {
  GridSummary summary;
  summary.skipped = skipped;
  std::int64_t pending_episodes = 0;
  double pending_cost_s = 0.0;
  for (std::size_t i = 0; i < pending.size(); ++i) {
    pending_episodes += pending[i].spec.budget;
    pending_cost_s += run_cost_s.at(i);
  }
  const int n_workers = std::max(1, std::min<int>(jobs, static_cast<int>(pending.size())));
  Progress progress(static_cast<std::int64_t>(pending.size()), pending_episodes, pending_cost_s, n_workers,
                    progress_out);
  if (progress_out && summary.skipped > 0)
    std::fprintf(progress_out, "resuming: %lld runs already done, %zu to run\n",
                 static_cast<long long>(summary.skipped), pending.size());
  progress.start();

  const std::atomic<bool>& stop = stop_requested();
  std::atomic<std::int64_t> n_done{0}, n_failed{0}, n_interrupted{0}, n_resumed{0}, n_replayed{0}, n_shared{0},
      n_shared_episodes{0}, n_recalled{0}, n_recomputed{0};
  std::mutex error_mutex;
  std::exception_ptr store_error;
  std::mutex finished_mutex;
  // which run a worker takes: the first in order not taken whose lead (sharing) has ended
  const std::vector<std::ptrdiff_t> lead =
      share && !leads.empty() ? leads : std::vector<std::ptrdiff_t>(pending.size(), -1);
  std::mutex queue_mutex;
  std::condition_variable queue_changed;
  std::vector<char> taken(pending.size(), 0), ended(pending.size(), 0);
  std::size_t first_open = 0;  // every run before it is taken
  bool abandon = false;        // a store error: no new run
  auto take_next = [&]() -> std::optional<std::size_t> {
    std::unique_lock lock(queue_mutex);
    for (;;) {
      if (stop.load() || abandon) return std::nullopt;  // no new run after a stop request
      while (first_open < pending.size() && taken[first_open]) ++first_open;
      if (first_open == pending.size()) return std::nullopt;
      for (std::size_t i = first_open; i < pending.size(); ++i)
        if (!taken[i] && (lead[i] < 0 || ended[static_cast<std::size_t>(lead[i])])) {
          taken[i] = 1;
          return i;
        }
      // every open run waits for a lead that runs now: wait for a run to end (or a stop)
      queue_changed.wait_for(lock, std::chrono::milliseconds(200));
    }
  };
  auto run_ended = [&](std::size_t i) {
    {
      std::lock_guard lock(queue_mutex);
      ended[i] = 1;
    }
    queue_changed.notify_all();
  };
  auto worker = [&](int w) {
    ThreadTeam team(threads);  // this job's threads, reused by all its runs
    for (;;) {
      const auto next_run = take_next();
      if (!next_run) return;
      const std::size_t i = *next_run;
      const PlannedRun& p = pending[i];
      try {
        RunStart start = store.begin_run(p.key, p.spec.rng_seed, p.spec.env_config->config, p.spec.opt_config->config,
                                         share && p.spec.may_share_seeds());
        if (start.committed_episodes > 0 && start.journal.empty()) {
          // episodes without the journal that regenerates them (e.g. left by an older harness):
          // nothing to replay, so the run starts over
          store.reset_progress(start.run_id);
          start.committed_episodes = 0;
        }
        const Env& env = *p.spec.resolved_env;
        progress.run_started(w, run_cost_s[i] / static_cast<double>(p.spec.budget));
        RunResult r;
        const std::int64_t shared_episodes = start.shared_episodes;
        // the run's CPU: its earlier sessions', since now this worker thread's and its thread
        // team's (the team works for this job's runs only, one at a time), and that of the
        // processes its optimizer started (an external program's: Optimizer::process_cpu_s)
        const ThreadCpuClock cpu_clock;
        const double cpu_at_start = cpu_clock.seconds() + team.workers_cpu_seconds();
        const double cpu_before = start.cpu_s;
        double ended_processes_cpu = 0.0;     // of the optimizers of earlier attempts
        const Optimizer* live_opt = nullptr;  // this attempt's
        const auto cpu_s = [&] {
          return cpu_before + (cpu_clock.seconds() + team.workers_cpu_seconds() - cpu_at_start) + ended_processes_cpu +
              (live_opt ? live_opt->process_cpu_s() : 0.0);
        };
        for (int attempt = 0;; ++attempt) {
          // a resumed run replays its journal, a run of a later seed the seed-free episodes of an
          // earlier one; one that diverged from it starts over without
          const auto opt = p.spec.new_optimizer();
          live_opt = opt.get();
          CommitListener listener(store, start.run_id, start.committed_episodes, cpu_s);
          RunControl control{&listener, &stop, std::move(start.journal), start.journal_episodes, tape_memory_bytes};
          r = execute_run(p.spec, env, *opt, &progress.episodes_of(w), &team, &control);
          ended_processes_cpu += opt->process_cpu_s();
          live_opt = nullptr;
          if (r.status != RunStatus::diverged || attempt > 0) break;
          if (progress_out)
            std::fprintf(progress_out, "\nharness: %s: %s; running it again from the start\n", p.key.text().c_str(),
                         r.error.c_str());
          store.reset_progress(start.run_id);
          start = RunStart{start.run_id, 0, {}};
        }
        fault_maybe_kill(progress.episodes());
        if (start.committed_episodes > 0) {
          n_resumed.fetch_add(1);
          n_replayed.fetch_add(r.replayed_episodes);
          n_recalled.fetch_add(r.recalled_work);
          n_recomputed.fetch_add(r.recomputed_work);
        } else if (shared_episodes > 0 && start.journal_episodes > 0) {
          n_shared.fetch_add(1);
          n_shared_episodes.fetch_add(shared_episodes);
        }
        if (r.status == RunStatus::interrupted) {
          n_interrupted.fetch_add(1);
          run_ended(i);
          continue;  // committed; the next harness resumes it
        }
        if (r.status == RunStatus::diverged) r.status = RunStatus::failed;
        r.cpu_s = cpu_s();
        store.finish_run(start.run_id, r);
        run_ended(i);
        (r.status == RunStatus::done ? n_done : n_failed).fetch_add(1);
        progress.run_finished(w, r.status != RunStatus::done, run_cost_s[i]);
        if (on_run_finished) {
          std::lock_guard lock(finished_mutex);
          on_run_finished();
        }
      } catch (...) {
        // a store failure stops the grid; runs already committed stay
        {
          std::lock_guard lock(error_mutex);
          if (!store_error) store_error = std::current_exception();
        }
        {
          std::lock_guard lock(queue_mutex);
          abandon = true;
        }
        queue_changed.notify_all();
        return;
      }
    }
  };
  std::vector<std::thread> workers;
  for (int t = 0; t < n_workers; ++t) workers.emplace_back(worker, t);
  for (auto& t : workers) t.join();
  if (store_error) std::rethrow_exception(store_error);
  summary.done = n_done.load();
  summary.failed = n_failed.load();
  summary.interrupted = n_interrupted.load();
  summary.resumed = n_resumed.load();
  summary.replayed_episodes = n_replayed.load();
  summary.recalled_work = n_recalled.load();
  summary.recomputed_work = n_recomputed.load();
  summary.shared_runs = n_shared.load();
  summary.shared_episodes = n_shared_episodes.load();
  return summary;
}

}  // namespace dsb
