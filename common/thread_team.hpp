#pragma once
// A fixed team of threads for the work inside one rollout (or one batch of rollouts). The caller
// is thread 0; size() - 1 workers wait on a condition variable between jobs, so a job costs a
// wake-up, not a thread start. A job is a number of tasks taken dynamically: which thread runs a
// task is not deterministic, so callers that need bit-identical results write each task's result
// to that task's own slot and combine slots in task order (common/parallel.hpp does exactly that).
// A job started from inside a task of a team (a nested parallel loop) runs serially on the calling
// thread: a batch spread over the team evaluates each rollout serially, with the same bits.
// Waiting: a worker that finished a job, and the caller waiting for its workers, first spin for
// up to kSpinMicros (an MPM substep starts a dozen short jobs, and a condition variable's wake-up
// costs tens of microseconds each time), then sleep on the condition variable.
// Chosen over TBB: tbb::parallel_reduce's split points depend on the number of threads and on
// stealing; its deterministic variant fixes the splits but ties them to the grain and range only,
// which is what we do here in a hundred lines with no dependency.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/thread_cpu_clock.hpp"

namespace dsb {

inline void spin_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Spins until done() or about `micros` microseconds have passed; returns done().
template <class Done>
bool spin_until(Done&& done, int micros) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::microseconds(micros);
  for (int i = 1;; ++i) {
    if (done()) return true;
    spin_pause();
    if ((i & 63) == 0 && std::chrono::steady_clock::now() > deadline) return done();
  }
}

// A non-owning reference to a callable void(int): no allocation, unlike std::function.
class TaskRef {
 public:
  template <class F>
  TaskRef(F& f) : object_(static_cast<void*>(&f)), call_([](void* o, int i) { (*static_cast<F*>(o))(i); }) {}
  void operator()(int i) const { call_(object_, i); }

 private:
  void* object_;
  void (*call_)(void*, int);
};

class ThreadTeam {
 public:
  // threads >= 1 (1: everything runs on the calling thread, no worker is started)
  explicit ThreadTeam(int threads) {
    if (threads < 1) throw std::invalid_argument("ThreadTeam: threads must be >= 1, got " + std::to_string(threads));
    workers_.reserve(static_cast<std::size_t>(threads - 1));
    for (int t = 1; t < threads; ++t) workers_.emplace_back([this, t] { worker_loop(t); });
  }
  ~ThreadTeam() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    start_.notify_all();
    for (auto& w : workers_) w.join();
  }
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  // The CPU seconds the workers (threads 1 .. size() - 1, not the caller) have used since they
  // started, spinning included: the team's share of a run is the difference over it (a run's
  // runs.cpu_s with --threads above 1). Read from any thread; 0 for a team of one.
  double workers_cpu_seconds() {
    double s = 0.0;
    for (auto& w : workers_) s += ThreadCpuClock(w.native_handle()).seconds();
    return s;
  }

  // Runs task(i) for every i in [0, tasks) and returns when all are done. The first exception
  // thrown by a task is rethrown here (the remaining tasks are skipped).
  template <class F>
  void run(int tasks, F&& task) {
    dispatch(tasks, task, false);
  }

  // Runs task(t) once for every thread t in [0, size()), on thread t itself (the caller is 0):
  // for work split into one contiguous part per thread that should stay on the same core from one
  // job to the next (cache locality). Nested or on a team of one, the calls run in order on the
  // calling thread. Callers must not let results depend on the split (e.g. disjoint writes).
  template <class F>
  void run_per_thread(F&& task) {
    dispatch(size(), task, true);
  }

  static constexpr int kSpinMicros = 50;

 private:
  template <class F>
  void dispatch(int tasks, F& task, bool per_thread) {
    if (tasks <= 0) return;
    if (workers_.empty() || tasks == 1 || inside_task()) {
      for (int i = 0; i < tasks; ++i) task(i);
      return;
    }
    auto& f = task;
    TaskRef ref(f);
    {
      std::lock_guard lock(mutex_);
      job_ = &ref;
      per_thread_ = per_thread;
      tasks_ = tasks;
      next_.store(0, std::memory_order_relaxed);
      busy_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
      error_ = nullptr;
      generation_.fetch_add(1, std::memory_order_release);
    }
    start_.notify_all();
    work(ref, tasks, per_thread ? 0 : -1);
    auto idle = [this] { return busy_.load(std::memory_order_acquire) == 0; };
    if (!spin_until(idle, kSpinMicros)) {
      std::unique_lock lock(mutex_);
      done_.wait(lock, idle);
    }
    std::lock_guard lock(mutex_);
    job_ = nullptr;
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

  static bool& inside_task() {
    thread_local bool inside = false;
    return inside;
  }

  // takes tasks until none is left, or (own >= 0) runs task `own` only
  void work(const TaskRef& job, int tasks, int own) {
    inside_task() = true;
    auto one = [&](int i) {
      try {
        job(i);
      } catch (...) {
        std::lock_guard lock(mutex_);
        if (!error_) error_ = std::current_exception();
        next_.store(tasks, std::memory_order_relaxed);
      }
    };
    if (own >= 0) {
      one(own);
    } else {
      for (int i; (i = next_.fetch_add(1, std::memory_order_relaxed)) < tasks;) one(i);
    }
    inside_task() = false;
  }

  void worker_loop(int index) {
    std::uint64_t seen = 0;
    for (;;) {
      const TaskRef* job;
      int tasks;
      bool per_thread;
      // a new job soon after the last one is caught spinning; otherwise sleep
      spin_until([&] { return generation_.load(std::memory_order_acquire) != seen; }, kSpinMicros);
      {
        std::unique_lock lock(mutex_);
        start_.wait(lock, [&] { return stop_ || generation_.load(std::memory_order_relaxed) != seen; });
        if (stop_) return;
        seen = generation_.load(std::memory_order_relaxed);
        job = job_;
        tasks = tasks_;
        per_thread = per_thread_;
      }
      work(*job, tasks, per_thread ? index : -1);
      if (busy_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        std::lock_guard lock(mutex_);  // the caller checks busy_ under the mutex before sleeping
        done_.notify_one();
      }
    }
  }

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  const TaskRef* job_ = nullptr;
  int tasks_ = 0;
  bool per_thread_ = false;
  std::atomic<int> next_{0};
  std::atomic<int> busy_{0};
  std::atomic<std::uint64_t> generation_{0};
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace dsb
