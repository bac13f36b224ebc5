#pragma once
// A memo of an optimizer's own costly work (a GP's hyperparameter fit, an acquisition's argmin),
// so that a resumed run skips what its interrupted attempt already computed. The harness keeps it
// in the run's journal beside the objective's answers (harness/core/replay.hpp): a resumed run recalls
// the results in the order they were remembered, then computes live. An optimizer may only put
// through it a result that is a pure function of what its key digests, and must then do exactly
// what it does with a result it computed (draw the same values from its Rng, count the same
// things), so that a run's results never depend on whether it was resumed.
//
// Use: recall(key, out) before the work; true: out holds the result. false: compute it, then
// remember(key, result). The default remembers nothing (every result is computed).
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>

#include "common/rng.hpp"

namespace dsb {

class WorkMemo {
 public:
  virtual ~WorkMemo() = default;
  // the result remembered under `key` at this point of the run, written to out (whose size is
  // the result's); false when there is none
  virtual bool recall(std::uint64_t /*key*/, std::span<double> /*out*/) { return false; }
  virtual void remember(std::uint64_t /*key*/, std::span<const double> /*result*/) {}
};

// where a key's digest starts (FNV-1a's offset basis)
inline constexpr std::uint64_t kWorkKeyStart = 0xcbf29ce484222325ULL;

// a key: FNV-1a folded over the bytes of values (bit-exact), starting from h
inline std::uint64_t work_key(std::uint64_t h, std::span<const double> values) {
  if (values.empty()) return h;
  return fnv1a64(std::string_view(reinterpret_cast<const char*>(values.data()), values.size_bytes()), h);
}

inline std::uint64_t work_key(std::uint64_t h, std::uint64_t value) {
  char bytes[sizeof value];
  std::memcpy(bytes, &value, sizeof value);
  return fnv1a64(std::string_view(bytes, sizeof bytes), h);
}

}  // namespace dsb
