#pragma once
// An env family: a name pattern (e.g. "sphere-D" for any D) and the factory of its members. Each
// family's header declares one (cartpole_family(), plb_family(), ...); the registry one folder up
// (envs/registry.cpp) lists them, so a family never includes the registry.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "envs/core/env.hpp"
#include "envs/core/env_options.hpp"

namespace dsb {

struct EnvFamily {
  std::string pattern;  // shown by `harness list`, e.g. "rosenbrock-D"
  std::string description;
  std::vector<std::string> grid_names;  // the members `--all` runs
  // returns an env when the name belongs to this family; throws UsageError for a member name
  // with a bad parameter (e.g. "sphere-0")
  std::function<std::unique_ptr<Env>(const std::string& name)> try_make;
  // the options its envs take (--set ENV.KEY=VALUE; empty: none), and the factory that applies
  // them to a member name (called with keys of `options` only, at least one)
  std::vector<EnvOptionInfo> options = {};
  // The results version of every member (docs/database.md "Results versions"), set beside the
  // family's registration line in envs/registry.cpp: the commit that changes any member's losses,
  // gradients, RL view or config bumps it. Part of every run key.
  int results_version = 1;
  std::function<std::unique_ptr<Env>(const std::string& name, const EnvOptions& options)> make_with_options = {};
};

// A family of one env without variants (`bounce`, `flip`): `name` is its pattern and its one grid
// member, `make` builds it; a variant of the name ("NAME-x", "NAME_x") is a UsageError saying that
// NAME takes none.
EnvFamily single_env_family(std::string name, std::string description, std::function<std::unique_ptr<Env>()> make);

}  // namespace dsb
