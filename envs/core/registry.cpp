#include "envs/core/registry.hpp"

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
    // one registration line per env family
    f.push_back(cartpole_family(1));
    f.push_back(cartpole_family(3));
    f.push_back(pinball_family(1, 2));
    f.push_back(pinball_family(4, 4));
    f.push_back(bounce_family());
    f.push_back(cloth::swing_family());
    f.push_back(cloth::flip_family());
    f.push_back(mpm::fluid_family());
    f.push_back(mpm::plb_family());
    for (auto& s : synthetic_families()) f.push_back(std::move(s));
    return f;
  }();
  return families;
}

std::unique_ptr<Env> make_env(const std::string& name) {
  for (const auto& family : env_families())
    if (auto env = family.try_make(name)) return env;
  throw UsageError("unknown env '" + name + "' (see `harness list`)");
}

std::shared_ptr<const Env> shared_env(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Env>> envs;
  std::lock_guard lock(mutex);
  auto& slot = envs[name];
  if (!slot) {
    try {
      slot = make_env(name);
    } catch (...) {
      envs.erase(name);
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
