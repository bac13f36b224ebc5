#pragma once
// Progress of a grid: runs done/total, episodes per second and ETA. Counts episodes inside runs,
// so runs that take hours still show movement. On a terminal the line is redrawn in place; on a
// pipe or file a plain line is printed periodically.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

namespace dsb {

class Progress {
 public:
  Progress(std::int64_t total_runs, std::int64_t total_episodes, std::FILE* out);
  ~Progress();  // stops the printer and prints a final line
  void start();
  void run_finished(bool failed);
  std::atomic<std::int64_t>& episodes() { return episodes_; }
  std::string line() const;

 private:
  void loop();
  std::int64_t total_runs_, total_episodes_;
  std::FILE* out_;
  bool tty_;
  std::atomic<std::int64_t> episodes_{0}, runs_done_{0}, runs_failed_{0};
  std::chrono::steady_clock::time_point start_;
  std::thread printer_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
};

}  // namespace dsb
