#pragma once
// Mid-run resume by replay (docs/running.md "Running on a Slurm cluster"). While a run goes, the budget wrapper
// journals every objective call: what kind of call it was, a digest of its input (the point, the
// action) and what it returned (loss, metric, gradient, observation). The journal is committed
// with the episodes every few seconds. A resumed run starts again from its seed: the optimizer
// proposes the same points, and while a call's kind and input digest equal the journal's next
// entry the recorded answer is served instead of simulating; from the first call past the
// journal (or one that differs) the run goes on live. A resumed run's evals therefore equal an
// uninterrupted run's. Entries are deleted when the run ends.
//
// The journal also keeps the results of the optimizer's own costly work (a GP's fits and
// acquisitions: optimizers/core/work_memo.hpp), one `own_work` entry each, in the order the run
// computed them: the input digest is the optimizer's key of the work, the payload its result. A
// resumed run recalls them in that order instead of computing them again. A journal without them
// (written before they were kept) still resumes, computing that work again.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/rng.hpp"

namespace dsb {

enum class ReplayKind : int { value = 0, value_and_grad = 1, rl_reset = 2, rl_step = 3, own_work = 4 };

// Thrown when a resumed run asks for something other than its journal's next entry (another
// binary, or a bug), or an entry's payload is not the size its kind has: the runner then restarts
// the run from nothing.
struct ReplayDiverged : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ReplayEntry {
  ReplayKind kind = ReplayKind::value;
  std::uint64_t input_hash = 0;
  // the answer, flattened (the database's BLOB); read and written only through the answer types
  // below: value and value_and_grad an EpisodeAnswer, rl_reset an observation, rl_step an
  // RlStepAnswer; own_work the optimizer's result as it gave it
  std::vector<double> payload;
};

// What a value or value_and_grad call returned: {loss, metric, wall_s} then, for value_and_grad,
// the gradient (dim values). The loss is the env's raw number (NaN or infinite when it failed).
struct EpisodeAnswer {
  double loss = 0.0, metric = 0.0, wall_s = 0.0;
  std::vector<double> gradient;  // empty for a value call

  std::vector<double> payload() const {
    std::vector<double> p = {loss, metric, wall_s};
    p.insert(p.end(), gradient.begin(), gradient.end());
    return p;
  }
  // gradient_size: 0 for a value entry, the env's dim for a value_and_grad one
  static EpisodeAnswer from(const ReplayEntry& e, std::size_t gradient_size) {
    if (e.payload.size() != 3 + gradient_size)
      throw ReplayDiverged("resume: a journal answer of " + std::to_string(e.payload.size()) + " values, expected " +
                           std::to_string(3 + gradient_size));
    return {e.payload[0], e.payload[1], e.payload[2], {e.payload.begin() + 3, e.payload.end()}};
  }
};

// What an RL decision returned: {done (1 or 0), the episode's raw final loss (0 until done), the
// episode's wall_s (0 until done), the env's second metric (NaN until done, and for an env
// without one)} then the observation. Journals written before the metric was kept lack it (3
// values before the observation): they are read with the metric NaN.
struct RlStepAnswer {
  bool done = false;
  double loss = 0.0, wall_s = 0.0, metric = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> observation;

  std::vector<double> payload() const {
    std::vector<double> p = {done ? 1.0 : 0.0, loss, wall_s, metric};
    p.insert(p.end(), observation.begin(), observation.end());
    return p;
  }
  static RlStepAnswer from(const ReplayEntry& e, std::size_t observation_size) {
    const std::size_t n = e.payload.size();
    if (n != 4 + observation_size && n != 3 + observation_size)
      throw ReplayDiverged("resume: a journal RL step of " + std::to_string(n) + " values, expected " +
                           std::to_string(4 + observation_size));
    const std::size_t head = n - observation_size;
    const double metric = head == 4 ? e.payload[3] : std::numeric_limits<double>::quiet_NaN();
    return {e.payload[0] != 0.0,
            e.payload[1],
            e.payload[2],
            metric,
            {e.payload.begin() + static_cast<std::ptrdiff_t>(head), e.payload.end()}};
  }
};

// A run's seed-free prefix: its episodes before the optimizer's first draw from the run's Rng
// (common/rng.hpp counts draws), and the journal entries (calls) that produced them. Those are
// the same for every seed of the same env, optimizer, configs, budget and harness version, so a
// run of another seed takes them by replay instead of simulating them (harness/store/store.hpp).
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
