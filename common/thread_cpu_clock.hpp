#pragma once
// The CPU time of one thread (its POSIX per-thread CPU clock, readable from any thread): what a run
// costs on its worker thread, apart from the runs beside it in the same process, whose process
// clock (getrusage) would mix them.
#include <pthread.h>
#include <time.h>

#include <limits>

namespace dsb {

class ThreadCpuClock {
 public:
  // the calling thread's clock
  ThreadCpuClock() : ThreadCpuClock(pthread_self()) {}
  // another thread's of this process (one of a ThreadTeam's workers)
  explicit ThreadCpuClock(pthread_t thread) : valid_(pthread_getcpuclockid(thread, &clock_) == 0) {}

  // the CPU seconds the thread has used since it started; NaN when its clock cannot be read
  double seconds() const {
    timespec ts{};
    if (!valid_ || clock_gettime(clock_, &ts) != 0) return std::numeric_limits<double>::quiet_NaN();
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  }

 private:
  clockid_t clock_{};
  bool valid_;
};

}  // namespace dsb
