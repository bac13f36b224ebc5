#pragma once
// Deterministic loops over [0, n) on a ThreadTeam. The range is cut into blocks of `grain`
// indices, block b = [b grain, min(n, (b + 1) grain)); the cut depends only on n and grain, never
// on the number of threads. parallel_for runs blocks in any order (each index must write only its
// own outputs). parallel_reduce folds each block left to right, block 0 starting from `init` and
// the others from `identity`, and then combines the block results in block order: the same bits
// for every team size, and for n <= grain exactly the serial loop `acc = fold(0, n, init)`.
// No floating-point atomics anywhere.
#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "common/thread_team.hpp"

namespace dsb {

inline std::int64_t block_count(std::int64_t n, std::int64_t grain) {
  if (grain < 1) throw std::invalid_argument("parallel loop: grain must be >= 1");
  return n <= 0 ? 0 : (n + grain - 1) / grain;
}

// body(begin, end) for every block
template <class Body>
void parallel_for(ThreadTeam& team, std::int64_t n, std::int64_t grain, Body&& body) {
  const std::int64_t blocks = block_count(n, grain);
  auto task = [&](int b) {
    const std::int64_t begin = b * grain;
    body(begin, std::min(n, begin + grain));
  };
  team.run(static_cast<int>(blocks), task);
}

// fold(begin, end, T acc) -> T folds a block into acc; combine(T left, T right) -> T
template <class T, class Fold, class Combine>
T parallel_reduce(ThreadTeam& team, std::int64_t n, std::int64_t grain, T init, T identity, Fold&& fold,
                  Combine&& combine) {
  const std::int64_t blocks = block_count(n, grain);
  if (blocks <= 1) return blocks == 0 ? init : fold(std::int64_t{0}, n, init);
  // one slot per block; up to 64 blocks without touching the heap
  std::array<T, 64> small;
  std::vector<T> large;
  T* partial = small.data();
  if (blocks > static_cast<std::int64_t>(small.size())) {
    large.resize(static_cast<std::size_t>(blocks));
    partial = large.data();
  }
  auto task = [&](int b) {
    const std::int64_t begin = b * grain;
    partial[b] = fold(begin, std::min(n, begin + grain), b == 0 ? init : identity);
  };
  team.run(static_cast<int>(blocks), task);
  T acc = partial[0];
  for (std::int64_t b = 1; b < blocks; ++b) acc = combine(acc, partial[b]);
  return acc;
}

// the common case: a sum of doubles (fold adds a block's terms to acc, left to right)
template <class Fold>
double parallel_sum(ThreadTeam& team, std::int64_t n, std::int64_t grain, double init, Fold&& fold) {
  return parallel_reduce<double>(team, n, grain, init, 0.0, fold, [](double a, double b) { return a + b; });
}

// body(begin, end) over one contiguous part of [0, n) per thread of the team, part t on thread t
// (run_per_thread): for loops whose iterations write disjoint data, so that the split cannot
// change results, and whose data should stay in each core's cache from one loop to the next.
template <class Body>
void parallel_for_per_thread(ThreadTeam& team, std::int64_t n, Body&& body) {
  const int parts = team.size();
  team.run_per_thread([&](int t) { body(n * t / parts, n * (t + 1) / parts); });
}

// dst = src (same size), each thread copying its part
template <class T>
void copy_in_parts(ThreadTeam& team, const std::vector<T>& src, std::vector<T>& dst) {
  dst.resize(src.size());
  parallel_for_per_thread(team, static_cast<std::int64_t>(src.size()), [&](std::int64_t begin, std::int64_t end) {
    std::copy(src.begin() + begin, src.begin() + end, dst.begin() + begin);
  });
}

// A team of one thread, for callers that have no team (convenience paths, tests).
inline ThreadTeam& serial_team() {
  thread_local ThreadTeam team(1);
  return team;
}

}  // namespace dsb
