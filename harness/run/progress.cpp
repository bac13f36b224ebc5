#include "harness/run/progress.hpp"

#include <unistd.h>

#include <algorithm>

#include <fmt/format.h>

namespace dsb {

Progress::Progress(std::int64_t total_runs, std::int64_t total_episodes, double total_cost_s, int workers,
                   std::FILE* out)
    : total_runs_(total_runs),
      total_episodes_(total_episodes),
      total_cost_s_(total_cost_s),
      out_(out),
      tty_(out && isatty(fileno(out)) == 1) {
  for (int w = 0; w < std::max(1, workers); ++w) slots_.push_back(std::make_unique<Slot>());
}

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

void Progress::run_started(int worker, double seconds_per_episode) {
  Slot& s = *slots_[static_cast<std::size_t>(worker)];
  s.run_start.store(s.episodes.load());
  s.per_episode_s.store(seconds_per_episode);
}

void Progress::run_finished(int worker, bool failed, double run_cost_s) {
  Slot& s = *slots_[static_cast<std::size_t>(worker)];
  s.per_episode_s.store(0.0);
  finished_cost_s_.fetch_add(run_cost_s);
  runs_done_.fetch_add(1);
  if (failed) runs_failed_.fetch_add(1);
}

std::int64_t Progress::episodes() const {
  std::int64_t n = 0;
  for (const auto& s : slots_) n += s->episodes.load();
  return n;
}

std::string Progress::line() const {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // the estimated work done: finished runs, and running runs' episodes at their estimated cost
  double done_s = finished_cost_s_.load();
  for (const auto& s : slots_)
    done_s += static_cast<double>(s->episodes.load() - s->run_start.load()) * s->per_episode_s.load();
  // the ETA: the speed seen so far once 2% of the estimated work is done; before that an
  // extrapolation from a few cheap runs or the first episodes of a GP run is noise (it printed
  // 50 hours for a 30-minute grid), so the plan's own estimate, the work left over the workers
  std::string eta = "--";
  const auto hms = [](double s) {
    return fmt::format("{:02d}:{:02d}:{:02d}", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60,
                       static_cast<int>(s) % 60);
  };
  if (total_cost_s_ > 0.0) {
    const double left_work = std::max(0.0, total_cost_s_ - done_s);
    if (elapsed > 1.0 && done_s >= 0.02 * total_cost_s_)
      eta = hms(left_work * elapsed / done_s);
    else
      eta = hms(left_work / static_cast<double>(slots_.size())) + " (planned)";
  }
  return fmt::format("runs {}/{} ({} failed), episodes {}/{}, elapsed {:.1f} s, {:.1f}% of the estimated work, ETA {}",
                     runs_done_.load(), total_runs_, runs_failed_.load(), episodes(), total_episodes_, elapsed,
                     total_cost_s_ > 0.0 ? 100.0 * std::min(1.0, done_s / total_cost_s_) : 0.0, eta);
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
