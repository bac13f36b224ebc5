#pragma once
// The key of a run, as the database stores it (runs' UNIQUE columns), and a grid's run with its
// key. Both plan/ and store/ speak of runs by these keys; neither sees the other.
#include <cstdint>
#include <string>
#include <tuple>

#include "harness/core/results_versions.hpp"
#include "harness/core/run_spec.hpp"

namespace dsb {

// the UNIQUE key of a run: runs of another harness version, config or results versions are other
// runs (a stored run whose results versions are not this binary's is stale: results_versions.hpp)
struct RunKey {
  std::string env, optimizer;
  int seed;
  std::int64_t budget;
  std::string env_config_hash, opt_config_hash;
  std::string harness_version;
  ResultsVersions versions = {};
  auto tie() const {
    return std::tie(env, optimizer, seed, budget, env_config_hash, opt_config_hash, harness_version, versions);
  }
  bool operator<(const RunKey& o) const { return tie() < o.tie(); }
  bool operator==(const RunKey& o) const { return tie() == o.tie(); }
  // "env/optimizer/seed S/budget B/config E,O/version V/results env E, optimizer O, run R", for messages
  std::string text() const;
  // the run's seed group, its key but the seed: "env\0optimizer\0budget\0env config\0optimizer
  // config\0version\0results versions\0" (runs of one group share their seed-free episodes)
  std::string group() const;
};

// a run of a grid with its key (plan/plan.hpp makes them; run/ runs them)
struct PlannedRun {
  RunSpec spec;
  RunKey key;
  // a done run of its group keeps its seed-free episodes in the database (plan/plan.hpp's
  // estimate_sharing): it replays them from there, and waits for no lead
  bool donor_stored = false;
};

}  // namespace dsb
