#include "envs/registry.hpp"

#include <map>
#include <mutex>

#include "common/error.hpp"
#include "envs/cloth/flip_env.hpp"
#include "envs/cloth/swing_env.hpp"
#include "envs/mpm/fluid_env.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/rigid/bounce_env.hpp"
#include "envs/rigid/cartpole_env.hpp"
#include "envs/rigid/pinball_env.hpp"
#include "envs/synthetic/synthetic.hpp"

namespace dsb {

const std::vector<EnvFamily>& env_families() {
  static const std::vector<EnvFamily> families = [] {
    std::vector<EnvFamily> f;
    // one registration line per env family, with its results version (bumped by the commit that
    // changes the family's results: docs/database.md "Results versions")
    const auto add = [&](EnvFamily family, int results_version) {
      family.results_version = results_version;
      f.push_back(std::move(family));
    };
    add(cartpole_family(1), 1);
    add(cartpole_family(3), 1);
    add(pinball_family(1, 2), 1);
    add(pinball_family(4, 4), 1);
    add(bounce_family(), 1);
    add(cloth::swing_family(), 1);
    add(cloth::flip_family(), 1);
    add(mpm::fluid_family(), 1);
    add(mpm::plb_family(), 2);  // 2: targets shaped like PlasticineLab's, TripleMove observes 205 particles
    for (auto& s : synthetic_families()) add(std::move(s), 1);  // sphere-D, ..., branin, hartmann6
    return f;
  }();
  return families;
}

namespace {

// UsageError naming the first key the family does not take
void check_option_keys(const EnvFamily& family, const std::string& name, const EnvOptions& options) {
  std::string known;
  for (const auto& o : family.options) known += (known.empty() ? "" : ", ") + o.key;
  for (const auto& [key, value] : options) {
    bool found = false;
    for (const auto& o : family.options) found = found || o.key == key;
    if (found) continue;
    if (known.empty())
      throw UsageError("env '" + name + "' takes no options, got '" + key + "' (--set " + name + "." + key + ")");
    throw UsageError("env '" + name + "' has no option '" + key + "' (its options: " + known + ")");
  }
}

}  // namespace

const EnvFamily& env_family_of(const std::string& name) {
  for (const auto& family : env_families())
    if (family.try_make(name)) return family;
  throw UsageError("unknown env '" + name + "' (see `harness list`)");
}

int env_results_version(const std::string& name) {
  for (const auto& family : env_families()) {
    try {
      if (family.try_make(name)) return family.results_version;
    } catch (const UsageError&) {
      return 0;  // a member name with a bad parameter (sphere-0): no env of ours
    }
  }
  return 0;
}

std::unique_ptr<Env> make_env(const std::string& name, const EnvOptions& options) {
  for (const auto& family : env_families()) {
    auto env = family.try_make(name);
    if (!env) continue;
    if (options.empty()) return env;
    check_option_keys(family, name, options);
    return family.make_with_options(name, options);
  }
  throw UsageError("unknown env '" + name + "' (see `harness list`)");
}

std::shared_ptr<const Env> shared_env(const std::string& name, const EnvOptions& options) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, EnvOptions>, std::shared_ptr<const Env>> envs;
  std::lock_guard lock(mutex);
  const auto key = std::make_pair(name, options);
  auto& slot = envs[key];
  if (!slot) {
    try {
      slot = make_env(name, options);
    } catch (...) {
      envs.erase(key);
      throw;
    }
  }
  return slot;
}

std::vector<std::string> grid_env_names() {
  std::vector<std::string> names;
  for (const auto& family : env_families())
    names.insert(names.end(), family.grid_names.begin(), family.grid_names.end());
  return names;
}

}  // namespace dsb
