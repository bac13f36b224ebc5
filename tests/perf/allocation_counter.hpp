#pragma once
// Counts heap allocations: replaces the global operator new of the benchmark binary that includes
// this header (include it in exactly one source file of a binary), and reports allocations per
// iteration as a Google Benchmark counter.
#include <atomic>
#include <cstdlib>
#include <new>

#include <benchmark/benchmark.h>

namespace dsb::perf {
inline std::atomic<long long> g_allocations{0};
}  // namespace dsb::perf

void* operator new(std::size_t n) {
  dsb::perf::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
// GCC flags free() on memory from operator new; here operator new is malloc, so it matches
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace dsb::perf {

// heap allocations per iteration since construction, as the counter "allocs/rollout"
struct AllocationCounter {
  long long start = g_allocations.load();
  void report(benchmark::State& state) const {
    state.counters["allocs/rollout"] =
        benchmark::Counter(static_cast<double>(g_allocations.load() - start) / static_cast<double>(state.iterations()));
  }
};

}  // namespace dsb::perf
