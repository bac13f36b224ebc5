#pragma once
// Own random number generation: SplitMix64 seeding, xoshiro256** stream, own uniform and normal
// samplers. std::*_distribution differs between standard libraries, so nothing here uses it.
#include <cmath>
#include <cstdint>
#include <string_view>

#include "common/det_math.hpp"

namespace dsb {

// splitmix64 step (Steele, Lea, Flood 2014): advances s and returns a well-mixed 64-bit value
inline std::uint64_t splitmix64(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// xoshiro256** (Blackman, Vigna 2018), state seeded from one 64-bit seed through splitmix64
class Rng {
 public:
  explicit Rng(std::uint64_t seed) {
    std::uint64_t s = seed;
    for (auto& w : state_) w = splitmix64(s);
  }

  std::uint64_t next_u64() {
    ++draws_;
    return advance();
  }

  // The next value without counting it as a draw: for a value no result depends on (a seed for a
  // generator that the algorithm at hand never uses). Advances the stream exactly as next_u64.
  std::uint64_t skip_u64() { return advance(); }

  // values drawn so far (next_u64 and everything built on it, skip_u64 not counted): a run's
  // episodes before its first draw are the same for every seed (harness/run/budget.hpp)
  std::uint64_t draws() const { return draws_; }

 private:
  std::uint64_t advance() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

 public:
  // uniform in [0, 1) with 53 random bits
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }

  // uniform in [lo, hi)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  // uniform integer in [0, n), n > 0 (Lemire's multiply-shift without the rejection bias fix is
  // biased by < n / 2^64, which is irrelevant here; kept simple and deterministic)
  std::uint64_t below(std::uint64_t n) {
    return static_cast<std::uint64_t>((static_cast<unsigned __int128>(next_u64()) * n) >> 64);
  }

  // standard normal by Marsaglia's polar method; the second value of each pair is cached
  double normal() {
    if (has_cached_) {
      has_cached_ = false;
      return cached_;
    }
    double u, v, s;
    do {
      u = 2.0 * uniform() - 1.0;
      v = 2.0 * uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double f = std::sqrt(-2.0 * dm::log(s) / s);
    cached_ = u * f;
    has_cached_ = true;
    return v * f;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t state_[4];
  std::uint64_t draws_ = 0;
  double cached_ = 0.0;
  bool has_cached_ = false;
};

// FNV-1a 64-bit hash of a byte string (content hashes of configs, per-run seeds)
constexpr std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t h = 0xcbf29ce484222325ULL) {
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace dsb
