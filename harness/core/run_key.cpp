#include "harness/core/run_key.hpp"

namespace dsb {

std::string RunKey::text() const {
  return env + "/" + optimizer + "/seed " + std::to_string(seed) + "/budget " + std::to_string(budget) + "/config " +
      env_config_hash + "," + opt_config_hash + "/version " + harness_version + "/results " +
      (versions.text().empty() ? std::string("unversioned") : versions.text());
}

std::string RunKey::group() const {
  std::string g;
  for (const std::string& part :
       {env, optimizer, std::to_string(budget), env_config_hash, opt_config_hash, harness_version, versions.text()}) {
    g += part;
    g.push_back('\0');
  }
  return g;
}

}  // namespace dsb
