#pragma once
// Progress of a grid: runs done/total, episodes, and an ETA from the cost model
// (harness/plan/cost_model.hpp): the share of the grid's estimated work that is done (finished runs,
// plus the episodes of running runs at their estimated cost each), extrapolated at the speed seen
// so far once 2% of it is done (the plan's estimate before that). Counts episodes inside runs, so
// runs that take hours still show movement. On a terminal the line is redrawn in place; on a pipe
// or file a plain line is printed periodically.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace dsb {

class Progress {
 public:
  // total_cost_s: the estimated seconds of all the runs to do; workers: the runs at once
  Progress(std::int64_t total_runs, std::int64_t total_episodes, double total_cost_s, int workers, std::FILE* out);
  ~Progress();  // stops the printer and prints a final line
  void start();
  // worker w's episode counter (the budget wrapper increments it)
  std::atomic<std::int64_t>& episodes_of(int worker) { return slots_[static_cast<std::size_t>(worker)]->episodes; }
  void run_started(int worker, double seconds_per_episode);
  void run_finished(int worker, bool failed, double run_cost_s);
  std::int64_t episodes() const;
  std::string line() const;

 private:
  struct Slot {
    std::atomic<std::int64_t> episodes{0};
    std::atomic<std::int64_t> run_start{0};
    std::atomic<double> per_episode_s{0.0};
  };
  void loop();
  std::int64_t total_runs_, total_episodes_;
  double total_cost_s_;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::FILE* out_;
  bool tty_;
  std::atomic<std::int64_t> runs_done_{0}, runs_failed_{0};
  std::atomic<double> finished_cost_s_{0.0};
  std::chrono::steady_clock::time_point start_;
  std::thread printer_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
};

}  // namespace dsb
