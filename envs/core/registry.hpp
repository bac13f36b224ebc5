#pragma once
// Envs by name. A family owns a name pattern (e.g. "sphere-D" for any D) and a factory; the
// registry lists families in envs/core/registry.cpp, one registration line each.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "envs/core/env.hpp"
#include "envs/core/env_options.hpp"

namespace dsb {

struct EnvFamily {
  std::string pattern;                    // shown by `harness list`, e.g. "rosenbrock-D"
  std::string description;
  std::vector<std::string> grid_names;    // the members `--all` runs
  // returns an env when the name belongs to this family; throws UsageError for a member name
  // with a bad parameter (e.g. "sphere-0")
  std::function<std::unique_ptr<Env>(const std::string& name)> try_make;
  // the options its envs take (--set ENV.KEY=VALUE; empty: none), and the factory that applies
  // them to a member name (called with keys of `options` only, at least one)
  std::vector<EnvOptionInfo> options = {};
  std::function<std::unique_ptr<Env>(const std::string& name, const EnvOptions& options)> make_with_options = {};
};

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

// Every env of the `--all` grid, in registration order.
std::vector<std::string> grid_env_names();

}  // namespace dsb
