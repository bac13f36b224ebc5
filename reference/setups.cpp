// The cross-check's setups, one registration line per rigid env (each entry is defined beside
// its setup), and what is looked up by env name.
#include <algorithm>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "reference/setup.hpp"

namespace dsb::reference {

const std::vector<SetupEntry>& setup_entries() {
  static const std::vector<SetupEntry> entries = {
      cartpole_setup(1), cartpole_setup(3), bounce_setup(), pinball_setup(1, 2), pinball_setup(4, 4),
  };
  return entries;
}

const std::vector<std::string>& crosscheck_envs() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& e : setup_entries()) n.push_back(e.env);
    return n;
  }();
  return names;
}

std::unique_ptr<CrosscheckSetup> make_setup(const std::string& env) {
  const auto& entries = setup_entries();
  const auto it = std::find_if(entries.begin(), entries.end(), [&](const auto& e) { return e.env == env; });
  if (it == entries.end()) {
    std::string known;
    for (const auto& n : crosscheck_envs()) known += (known.empty() ? "" : ", ") + n;
    throw UsageError("crosscheck: unknown env '" + env + "' (rigid envs: " + known + ")");
  }
  return it->make();
}

std::vector<std::vector<double>> crosscheck_vectors(const std::string& env) {
  // fixed seed: the table is the same on every run
  constexpr std::uint64_t kSeed = 20220711;
  const auto setup = make_setup(env);
  Rng rng(kSeed ^ fnv1a64(env));
  return setup->vectors(rng);
}

Tolerances crosscheck_tolerances(const std::string& env, const std::string& engines) {
  return make_setup(env)->tolerances(engines);
}

}  // namespace dsb::reference
