// Own RNG: reproducible streams, correct moments of the uniform and normal samplers, per-run seeds.
#include <cmath>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.hpp"
#include "harness/core/run_spec.hpp"

namespace dsb {
namespace {

TEST(Rng, SplitMix64MatchesTheReferenceSequence) {
  // first outputs of splitmix64 seeded with 0 (published reference values of the algorithm)
  std::uint64_t s = 0;
  EXPECT_EQ(splitmix64(s), 0xe220a8397b1dcdafULL);
  EXPECT_EQ(splitmix64(s), 0x6e789e6aa1b965f4ULL);
  EXPECT_EQ(splitmix64(s), 0x06c45d188009454fULL);
}

TEST(Rng, SameSeedSameStreamDifferentSeedDifferentStream) {
  Rng a(42), b(42), c(43);
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const auto va = a.next_u64();
    EXPECT_EQ(va, b.next_u64());
    differs = differs || va != c.next_u64();
  }
  EXPECT_TRUE(differs);
}

TEST(Rng, UniformMomentsAndRange) {
  Rng rng(7);
  const int n = 200000;
  double sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum2 += u * u;
  }
  const double mean = sum / n, var = sum2 / n - mean * mean;
  // standard errors: 1/sqrt(12 n) = 6.5e-4 for the mean
  EXPECT_NEAR(mean, 0.5, 4e-3);
  EXPECT_NEAR(var, 1.0 / 12.0, 2e-3);
}

TEST(Rng, NormalMomentsAndTails) {
  Rng rng(11);
  const int n = 200000;
  double sum = 0.0, sum2 = 0.0, sum4 = 0.0;
  int beyond2 = 0;
  for (int i = 0; i < n; ++i) {
    const double z = rng.normal();
    sum += z;
    sum2 += z * z;
    sum4 += z * z * z * z;
    beyond2 += std::abs(z) > 2.0;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0, 0.015);
  EXPECT_NEAR(sum4 / n, 3.0, 0.08);
  // P(|Z| > 2) = 0.0455
  EXPECT_NEAR(static_cast<double>(beyond2) / n, 0.0455, 0.003);
}

TEST(Rng, BelowIsInRangeAndCoversIt) {
  Rng rng(3);
  std::set<std::uint64_t> seen;
  for (int i = 0; i < 1000; ++i) {
    const auto v = rng.below(7);
    ASSERT_LT(v, 7u);
    seen.insert(v);
  }
  EXPECT_EQ(seen.size(), 7u);
}

TEST(PerRunSeed, DependsOnEveryPartOfTheKeyAndIsStable) {
  const auto s = per_run_seed("cartpole3", "cmaes", 0);
  EXPECT_EQ(s, per_run_seed("cartpole3", "cmaes", 0));
  EXPECT_NE(s, per_run_seed("cartpole3", "cmaes", 1));
  EXPECT_NE(s, per_run_seed("cartpole1", "cmaes", 0));
  EXPECT_NE(s, per_run_seed("cartpole3", "random", 0));
  // no ambiguity from concatenation
  EXPECT_NE(per_run_seed("ab", "c", 0), per_run_seed("a", "bc", 0));
}

}  // namespace
}  // namespace dsb
