#include "harness/progress.hpp"

#include <unistd.h>

#include <fmt/format.h>

namespace dsb {

Progress::Progress(std::int64_t total_runs, std::int64_t total_episodes, std::FILE* out)
    : total_runs_(total_runs), total_episodes_(total_episodes), out_(out),
      tty_(out && isatty(fileno(out)) == 1) {}

void Progress::start() {
  start_ = std::chrono::steady_clock::now();
  if (out_) printer_ = std::thread([this] { loop(); });
}

Progress::~Progress() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (printer_.joinable()) printer_.join();
  if (out_) std::fprintf(out_, "%s%s\n", tty_ ? "\r\033[K" : "", line().c_str());
}

void Progress::run_finished(bool failed) {
  runs_done_.fetch_add(1);
  if (failed) runs_failed_.fetch_add(1);
}

std::string Progress::line() const {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::int64_t eps = episodes_.load();
  const double rate = elapsed > 0.0 ? eps / elapsed : 0.0;
  std::string eta = "--";
  if (rate > 0.0 && eps > 0) {
    const double left = static_cast<double>(total_episodes_ - eps) / rate;
    eta = fmt::format("{:02d}:{:02d}:{:02d}", static_cast<int>(left / 3600),
                      static_cast<int>(left / 60) % 60, static_cast<int>(left) % 60);
  }
  return fmt::format("runs {}/{} ({} failed), episodes {}/{}, {:.0f} episodes/s, elapsed {:.1f} s, ETA {}",
                     runs_done_.load(), total_runs_, runs_failed_.load(), eps, total_episodes_, rate,
                     elapsed, eta);
}

void Progress::loop() {
  const auto period = tty_ ? std::chrono::milliseconds(500) : std::chrono::milliseconds(10000);
  std::unique_lock lock(mutex_);
  while (!cv_.wait_for(lock, period, [this] { return stop_; })) {
    if (tty_)
      std::fprintf(out_, "\r\033[K%s", line().c_str());
    else
      std::fprintf(out_, "%s\n", line().c_str());
    std::fflush(out_);
  }
}

}  // namespace dsb
