#include "harness/runner.hpp"

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include "envs/core/registry.hpp"
#include "harness/budget.hpp"
#include "harness/fault_injection.hpp"
#include "harness/plan.hpp"
#include "harness/progress.hpp"
#include "optimizers/core/registry.hpp"

namespace dsb {

RunResult execute_run(const RunSpec& spec, const Env& env, Optimizer& optimizer,
                      std::atomic<std::int64_t>* episode_counter, ThreadTeam* team) {
  RunResult result;
  const auto start = std::chrono::steady_clock::now();
  BudgetedObjective objective(env, spec.budget, episode_counter, team);
  Rng rng(spec.rng_seed);
  result.status = "done";
  try {
    optimizer.minimize(objective, rng);
  } catch (const BudgetExhausted&) {
    // the normal end: the budget is spent
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error = e.what();
  }
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.episodes = objective.used();
  result.failed_episodes = objective.failed_episodes();
  result.best_loss = objective.best_loss();
  result.best_x = objective.best_x();
  result.evals = objective.evals();
  result.diagnostics = {{"optimizer", optimizer.diagnostics()}, {"objective", objective.diagnostics()}};
  return result;
}

GridSummary run_grid(const std::vector<RunSpec>& grid, Store& store, int jobs, int threads,
                     std::FILE* progress_out) {
  GridSummary summary;
  const GridPlan plan = plan_grid(grid, store.done_keys());
  const std::vector<PlannedRun>& pending = plan.pending;
  summary.skipped = plan.skipped;

  Progress progress(static_cast<std::int64_t>(pending.size()), plan.pending_episodes, progress_out);
  if (progress_out && summary.skipped > 0)
    std::fprintf(progress_out, "resuming: %lld runs already done, %zu to run\n",
                 static_cast<long long>(summary.skipped), pending.size());
  progress.start();

  std::atomic<std::size_t> next{0};
  std::atomic<std::int64_t> n_done{0}, n_failed{0};
  std::mutex error_mutex;
  std::exception_ptr store_error;
  auto worker = [&] {
    ThreadTeam team(threads);  // this job's threads, reused by all its runs
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= pending.size()) return;
      const PlannedRun& p = pending[i];
      try {
        const std::int64_t run_id =
            store.begin_run(p.key, p.spec.rng_seed, p.env_config->config, p.opt_config->config);
        const auto env = shared_env(p.spec.env);
        const auto opt = make_optimizer(p.spec.optimizer);
        const RunResult r = execute_run(p.spec, *env, *opt, &progress.episodes(), &team);
        fault_maybe_kill(progress.episodes().load());
        store.finish_run(run_id, r);
        (r.status == "done" ? n_done : n_failed).fetch_add(1);
        progress.run_finished(r.status != "done");
      } catch (...) {
        // a store failure stops the grid; runs already committed stay
        std::lock_guard lock(error_mutex);
        if (!store_error) store_error = std::current_exception();
        next.store(pending.size());
        return;
      }
    }
  };
  const int n_workers = std::max(1, std::min<int>(jobs, static_cast<int>(pending.size())));
  std::vector<std::thread> workers;
  for (int t = 0; t < n_workers; ++t) workers.emplace_back(worker);
  for (auto& t : workers) t.join();
  if (store_error) std::rethrow_exception(store_error);
  summary.done = n_done.load();
  summary.failed = n_failed.load();
  return summary;
}

}  // namespace dsb
