#include "harness/core/run_spec.hpp"

#include <stdexcept>

#include "common/rng.hpp"

namespace dsb {

std::uint64_t per_run_seed(const std::string& env, const std::string& optimizer, int seed) {
  std::string key = env;
  key.push_back('\0');
  key += optimizer;
  key.push_back('\0');
  key += std::to_string(seed);
  std::uint64_t h = fnv1a64(key);
  return splitmix64(h);
}

std::unique_ptr<Optimizer> RunSpec::new_optimizer() const {
  if (ext) return make_ext_optimizer(*ext, env, rng_seed);
  if (!entry) throw std::logic_error("run " + env + "/" + optimizer + ": its optimizer was never resolved");
  return knobs.empty() ? entry->make() : entry->make_with(knobs);
}

bool RunSpec::may_share_seeds() const { return !ext && entry && entry->seed_use != SeedUse::at_start; }

}  // namespace dsb
