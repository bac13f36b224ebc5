#pragma once
// `harness ... --report DIR`: keeps the comparison report of a running grid up to date. After a
// run finishes, the report is rebuilt when the last build is at least kReportIntervalS old (on a
// thread of its own: the runs go on meanwhile), and once more at the end, so a first useful report
// exists early even when the whole grid needs days.
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace dsb {

inline constexpr double kReportIntervalS = 300.0;

class ReportRefresher {
 public:
  ReportRefresher(std::string db, std::string dir);
  ~ReportRefresher();   // waits for a build in progress; does not build
  void run_finished();  // a run ended: build when due
  int final_build();    // the last build (waits for one in progress); the report's exit code

 private:
  void loop();
  int build();
  std::string db_, dir_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false, stop_ = false, building_ = false;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace dsb
