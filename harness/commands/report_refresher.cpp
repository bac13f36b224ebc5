#include "harness/commands/report_refresher.hpp"

#include <cstdio>

#include "harness/commands/report_command.hpp"

namespace dsb {

ReportRefresher::ReportRefresher(std::string db, std::string dir)
    : db_(std::move(db)), dir_(std::move(dir)), last_(std::chrono::steady_clock::now()) {
  thread_ = std::thread([this] { loop(); });
}

ReportRefresher::~ReportRefresher() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ReportRefresher::run_finished() {
  {
    std::lock_guard lock(mutex_);
    pending_ = true;
  }
  cv_.notify_all();
}

int ReportRefresher::build() {
  try {
    const int rc = command_report(db_, dir_, "", /*quiet=*/true);
    if (rc > 128)
      std::fprintf(stderr, "harness: report not written to %s: its generator was killed by signal %d\n", dir_.c_str(),
                   rc - 128);
    else
      std::fprintf(stderr, "harness: report %s %s\n", rc == 0 ? "written to" : "FAILED, not written to", dir_.c_str());
    return rc;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harness: report not refreshed: %s\n", e.what());
    return 1;
  }
}

void ReportRefresher::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait_for(lock, std::chrono::seconds(5), [this] { return stop_; });
    if (stop_) return;
    const double since = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count();
    if (!pending_ || since < kReportIntervalS) continue;
    pending_ = false;
    building_ = true;
    lock.unlock();
    build();
    lock.lock();
    building_ = false;
    last_ = std::chrono::steady_clock::now();
    cv_.notify_all();
  }
}

int ReportRefresher::final_build() {
  {
    std::unique_lock lock(mutex_);
    stop_ = true;
    cv_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  return build();
}

}  // namespace dsb
