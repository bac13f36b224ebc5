#pragma once
// Envs by name. A family (envs/core/env_family.hpp) owns a name pattern (e.g. "sphere-D" for any D)
// and a factory; the registry lists the families in envs/registry.cpp, one registration line each.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"
#include "envs/core/env_options.hpp"

namespace dsb {

const std::vector<EnvFamily>& env_families();

// Throws UsageError "unknown env 'NAME'" when no family knows the name. A new, unshared object
// (cheap: no model is built until its first rollout; an option may read a small file). Options
// the env's family does not take are a UsageError naming the key; a bad value one naming the
// option and the problem.
std::unique_ptr<Env> make_env(const std::string& name, const EnvOptions& options = {});

// The family that knows the name; UsageError "unknown env 'NAME'" otherwise.
const EnvFamily& env_family_of(const std::string& name);

// The one object of this name and options in the process, made on first request: every run and
// thread that uses the env shares it, and so shares its lazily built model. Thread-safe.
std::shared_ptr<const Env> shared_env(const std::string& name, const EnvOptions& options = {});

// The results version of the env's family (EnvFamily::results_version), 0 for a name no family
// knows. Looks at names only: no env is made.
int env_results_version(const std::string& name);

// Every env of the `--all` grid, in registration order.
std::vector<std::string> grid_env_names();

}  // namespace dsb
