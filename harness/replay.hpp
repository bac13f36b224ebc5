#pragma once
// Mid-run resume by replay (docs/running.md "Running on a Slurm cluster"). While a run goes, the budget wrapper
// journals every objective call: what kind of call it was, a digest of its input (the point, the
// action) and what it returned (loss, metric, gradient, observation). The journal is committed
// with the episodes every few seconds. A resumed run starts again from its seed: the optimizer
// proposes the same points, and while a call's kind and input digest equal the journal's next
// entry the recorded answer is served instead of simulating; from the first call past the
// journal (or one that differs) the run goes on live. A resumed run's evals therefore equal an
// uninterrupted run's. Entries are deleted when the run ends.
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "common/rng.hpp"

namespace dsb {

enum class ReplayKind : int { value = 0, value_and_grad = 1, rl_reset = 2, rl_step = 3 };

struct ReplayEntry {
  ReplayKind kind = ReplayKind::value;
  std::uint64_t input_hash = 0;
  // value:          {raw loss, metric, wall_s}
  // value_and_grad: {raw loss, metric, wall_s, gradient (dim)}
  // rl_reset:       {observation}
  // rl_step:        {done, raw final loss, wall_s of the episode, observation}
  std::vector<double> payload;
};

// A run's seed-free prefix: its episodes before the optimizer's first draw from the run's Rng
// (common/rng.hpp counts draws), and the journal entries (calls) that produced them. Those are
// the same for every seed of the same env, optimizer, configs, budget and harness version, so a
// run of another seed takes them by replay instead of simulating them (harness/store.hpp).
struct SeedFreePrefix {
  std::int64_t episodes = 0, calls = 0;
  bool drew = false;  // false: the optimizer never drew, and the whole run is seed-free
};

// FNV-1a over the bytes of the doubles (bit-exact: -0.0 and 0.0 differ, as do NaN payloads)
inline std::uint64_t replay_input_hash(std::span<const double> input) {
  std::string bytes(input.size() * sizeof(double), '\0');
  if (!input.empty()) std::memcpy(bytes.data(), input.data(), bytes.size());
  return fnv1a64(bytes);
}

// the payload as stored (a BLOB of doubles in the machine's byte order: x86-64 only writes and
// reads these files, and a replay is only ever served to the same binary)
inline std::string replay_payload_bytes(const std::vector<double>& payload) {
  std::string bytes(payload.size() * sizeof(double), '\0');
  if (!payload.empty()) std::memcpy(bytes.data(), payload.data(), bytes.size());
  return bytes;
}

inline std::vector<double> replay_payload_from_bytes(const std::string& bytes) {
  std::vector<double> payload(bytes.size() / sizeof(double));
  if (!payload.empty()) std::memcpy(payload.data(), bytes.data(), payload.size() * sizeof(double));
  return payload;
}

}  // namespace dsb
