#include "harness/runner.hpp"

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <csignal>
#include <thread>

#include "common/config_hash.hpp"
#include "envs/core/registry.hpp"
#include "harness/budget.hpp"
#include "harness/progress.hpp"
#include "optimizers/core/registry.hpp"

namespace dsb {

RunResult execute_run(const RunSpec& spec, const Env& env, Optimizer& optimizer,
                      std::atomic<std::int64_t>* episode_counter) {
  RunResult result;
  const auto start = std::chrono::steady_clock::now();
  BudgetedObjective objective(env, spec.budget, episode_counter);
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

namespace {

// Fault injection for the interruption tests: DSB_FAULT_KILL_AFTER_EPISODES=K makes the process
// SIGKILL itself once K episodes have run in total (single job gives a deterministic point).
std::int64_t kill_after_episodes() {
  const char* v = std::getenv("DSB_FAULT_KILL_AFTER_EPISODES");
  return v ? std::atoll(v) : -1;
}

}  // namespace

GridSummary run_grid(const std::vector<RunSpec>& grid, Store& store, int jobs,
                     std::FILE* progress_out) {
  GridSummary summary;
  // resolve configs and skip runs already done
  struct Pending {
    RunSpec spec;
    RunKey key;
    nlohmann::json env_config, opt_config;
  };
  std::vector<Pending> pending;
  const auto done = store.done_keys();
  for (const auto& spec : grid) {
    const auto env = make_env(spec.env);
    const auto opt = make_optimizer(spec.optimizer);
    Pending p{spec, {}, env->config(), opt->config()};
    p.key = {spec.env, spec.optimizer, spec.seed, spec.budget, config_hash(p.env_config),
             config_hash(p.opt_config)};
    if (done.count(p.key)) {
      ++summary.skipped;
      continue;
    }
    pending.push_back(std::move(p));
  }

  std::int64_t total_episodes = 0;
  for (const auto& p : pending) total_episodes += p.spec.budget;
  Progress progress(static_cast<std::int64_t>(pending.size()), total_episodes, progress_out);
  if (progress_out && summary.skipped > 0)
    std::fprintf(progress_out, "resuming: %lld runs already done, %zu to run\n",
                 static_cast<long long>(summary.skipped), pending.size());
  progress.start();

  const std::int64_t kill_at = kill_after_episodes();
  std::atomic<std::size_t> next{0};
  std::atomic<std::int64_t> n_done{0}, n_failed{0};
  std::mutex error_mutex;
  std::exception_ptr store_error;
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= pending.size()) return;
      const Pending& p = pending[i];
      try {
        const std::int64_t run_id = store.begin_run(p.key, p.spec.rng_seed, p.env_config, p.opt_config);
        const auto env = make_env(p.spec.env);
        const auto opt = make_optimizer(p.spec.optimizer);
        const RunResult r = execute_run(p.spec, *env, *opt, &progress.episodes());
        if (kill_at >= 0 && progress.episodes().load() >= kill_at) std::raise(SIGKILL);
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
  const int n_threads = std::max(1, std::min<int>(jobs, static_cast<int>(pending.size())));
  std::vector<std::thread> threads;
  for (int t = 0; t < n_threads; ++t) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (store_error) std::rethrow_exception(store_error);
  summary.done = n_done.load();
  summary.failed = n_failed.load();
  return summary;
}

}  // namespace dsb
