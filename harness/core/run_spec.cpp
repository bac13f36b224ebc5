#include "harness/core/run_spec.hpp"

#include "common/rng.hpp"
#include "optimizers/registry.hpp"

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

std::unique_ptr<Optimizer> make_run_optimizer(const RunSpec& spec) {
  if (spec.ext) return make_ext_optimizer(*spec.ext, spec.env, spec.rng_seed);
  return make_optimizer(spec.optimizer, spec.knobs);
}

bool may_share_seeds(const RunSpec& spec) {
  return !spec.ext && optimizer_entry(spec.optimizer).seed_use != SeedUse::at_start;
}

}  // namespace dsb
