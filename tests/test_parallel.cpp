// The deterministic thread team and loops of common/: every task runs exactly once, errors come
// back to the caller, nested loops run serially, and reductions give the same bits for every team
// size (and the serial loop's bits when the range fits one block).
#include <atomic>
#include <cmath>
#include <thread>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include <mutex>
#include <thread>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "common/thread_cpu_clock.hpp"
#include "common/usable_cpus.hpp"

namespace dsb {
namespace {

TEST(ThreadTeam, RunsEveryTaskExactlyOnce) {
  for (const int threads : {1, 2, 4}) {
    ThreadTeam team(threads);
    EXPECT_EQ(team.size(), threads);
    for (int round = 0; round < 50; ++round) {  // many jobs on the same workers
      std::vector<std::atomic<int>> hits(137);
      team.run(137, [&](int i) { hits[i].fetch_add(1); });
      for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
    }
  }
}

TEST(ThreadTeam, RethrowsATaskErrorAndStaysUsable) {
  ThreadTeam team(3);
  EXPECT_THROW(team.run(40,
                        [](int i) {
                          if (i == 17) throw std::runtime_error("task 17");
                        }),
               std::runtime_error);
  std::atomic<int> n{0};
  team.run(40, [&](int) { n.fetch_add(1); });
  EXPECT_EQ(n.load(), 40);
  EXPECT_THROW(ThreadTeam(0), std::invalid_argument);
}

TEST(ThreadTeam, NestedJobsRunSeriallyOnTheCallingThread) {
  ThreadTeam team(2);
  std::vector<std::atomic<int>> inner_threads(8);
  team.run(8, [&](int i) {
    const auto me = std::this_thread::get_id();
    bool same = true;
    team.run(5, [&](int) { same = same && std::this_thread::get_id() == me; });
    inner_threads[i] = same ? 1 : 0;
  });
  for (const auto& v : inner_threads) EXPECT_EQ(v.load(), 1);
}

double serial_sum(const std::vector<double>& v, double init) {
  double acc = init;
  for (double x : v) acc += x * x;
  return acc;
}

TEST(ParallelReduce, SameBitsForEveryTeamSize) {
  Rng rng(11);
  std::vector<double> v(100003);
  for (double& x : v) x = rng.normal() * std::pow(10.0, rng.uniform(-8.0, 8.0));  // rounding matters
  auto fold = [&](std::int64_t b, std::int64_t e, double acc) {
    for (std::int64_t i = b; i < e; ++i) acc += v[i] * v[i];
    return acc;
  };
  const double one = parallel_sum(serial_team(), static_cast<std::int64_t>(v.size()), 1000, 3.0, fold);
  for (const int threads : {2, 3, 4}) {
    ThreadTeam team(threads);
    for (int rep = 0; rep < 5; ++rep)
      EXPECT_EQ(parallel_sum(team, static_cast<std::int64_t>(v.size()), 1000, 3.0, fold), one) << threads;
  }
  // the blocked order is a different rounding from the serial loop here (the test can tell them apart)
  EXPECT_NE(one, serial_sum(v, 3.0));
  // a range within one block is exactly the serial loop
  std::vector<double> small(v.begin(), v.begin() + 900);
  ThreadTeam team(2);
  EXPECT_EQ(parallel_sum(team, 900, 1000, 3.0, fold), serial_sum(small, 3.0));
  // more than 64 blocks (heap slots) and an empty range
  EXPECT_EQ(parallel_sum(team, static_cast<std::int64_t>(v.size()), 100, 3.0, fold),
            parallel_sum(serial_team(), static_cast<std::int64_t>(v.size()), 100, 3.0, fold));
  EXPECT_EQ(parallel_sum(team, 0, 100, 3.0, fold), 3.0);
}

TEST(ParallelFor, CoversTheRangeInBlocks) {
  ThreadTeam team(3);
  std::vector<int> seen(1001, 0);
  parallel_for(team, 1001, 64, [&](std::int64_t b, std::int64_t e) {
    EXPECT_EQ(b % 64, 0);
    EXPECT_LE(e - b, 64);
    for (std::int64_t i = b; i < e; ++i) ++seen[i];
  });
  for (int s : seen) ASSERT_EQ(s, 1);
}

TEST(ThreadTeam, RunPerThreadRunsPartTOnThreadT) {
  ThreadTeam team(3);
  for (int round = 0; round < 50; ++round) {
    std::vector<std::thread::id> ran(3);
    team.run_per_thread([&](int t) { ran[t] = std::this_thread::get_id(); });
    EXPECT_EQ(ran[0], std::this_thread::get_id()) << "part 0 on the caller";
    EXPECT_NE(ran[1], ran[0]);
    EXPECT_NE(ran[2], ran[0]);
    EXPECT_NE(ran[1], ran[2]);
    static std::vector<std::thread::id> first;
    if (round == 0) first = ran;
    EXPECT_EQ(ran, first) << "the same thread takes the same part every time";
  }
  // nested: every part in order on the calling thread
  std::vector<int> order;
  team.run(2, [&](int i) {
    if (i == 0) team.run_per_thread([&](int t) { order.push_back(t); });
  });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2}));
}

// spends `seconds` of the calling thread's CPU
void burn_cpu(double seconds) {
  const ThreadCpuClock clock;
  const double start = clock.seconds();
  while (clock.seconds() - start < seconds) {}
}

TEST(ThreadTeam, WorkersCpuSecondsCountTheWorkersButNotTheCaller) {
  // a run's runs.cpu_s with --threads above 1: its thread's CPU plus the team's workers' over it
  ThreadTeam team(3);
  const double before = team.workers_cpu_seconds();
  // the caller burns 0.3 s, each of the two workers 0.1 s
  team.run_per_thread([](int t) { burn_cpu(t == 0 ? 0.3 : 0.1); });
  const double spent = team.workers_cpu_seconds() - before;
  EXPECT_GE(spent, 0.2);
  EXPECT_LT(spent, 0.3) << "the caller's 0.3 s is not the workers'";
  EXPECT_EQ(ThreadTeam(1).workers_cpu_seconds(), 0.0);
}

TEST(ParallelFor, PerThreadPartsCoverTheRangeContiguously) {
  for (int threads : {1, 2, 3}) {
    ThreadTeam team(threads);
    std::vector<int> seen(1001, 0);
    std::mutex m;
    parallel_for_per_thread(team, 1001, [&](std::int64_t b, std::int64_t e) {
      std::lock_guard lock(m);
      for (std::int64_t i = b; i < e; ++i) ++seen[i];
    });
    for (int s : seen) ASSERT_EQ(s, 1);
  }
}

TEST(UsableCpus, AtLeastOne) { EXPECT_GE(usable_cpus(), 1); }

}  // namespace
}  // namespace dsb
