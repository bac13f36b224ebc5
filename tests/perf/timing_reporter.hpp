#pragma once
// Console reporter that also keeps each benchmark's real time per iteration (seconds), by full
// benchmark name, so a binary can print ratios of benchmarks measured in the same run; and
// run_benchmarks, every bench binary's main: run what the command line selects, then its summary.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

namespace dsb::perf {

class TimingReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs)
      if (r.run_type == Run::RT_Iteration && !r.error_occurred && r.iterations > 0)
        seconds_[r.benchmark_name()] = r.real_accumulated_time / static_cast<double>(r.iterations);
    ConsoleReporter::ReportRuns(runs);
  }
  // seconds per iteration, 0 when the benchmark did not run (filtered out)
  double seconds(const std::string& name) const {
    const auto it = seconds_.find(name);
    return it == seconds_.end() ? 0.0 : it->second;
  }

 private:
  std::map<std::string, double> seconds_;
};

// Initialize, refuse unknown flags (exit 1), run the selected benchmarks through a TimingReporter,
// print the binary's summary of same-run ratios from it, Shutdown; the process's exit code.
inline int run_benchmarks(int argc, char** argv, const std::function<void(const TimingReporter&)>& summary) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  TimingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  summary(reporter);
  benchmark::Shutdown();
  return 0;
}

}  // namespace dsb::perf
