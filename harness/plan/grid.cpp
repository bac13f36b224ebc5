#include "harness/plan/grid.hpp"

#include <algorithm>
#include <filesystem>
#include <set>

#include "common/config_hash.hpp"
#include "common/error.hpp"
#include "envs/registry.hpp"
#include "optimizers/registry.hpp"

namespace dsb {
namespace {

std::shared_ptr<const ResolvedConfig> resolved_config(nlohmann::json config) {
  std::string hash = config_hash(config);
  return std::make_shared<const ResolvedConfig>(ResolvedConfig{std::move(config), std::move(hash)});
}

}  // namespace

std::vector<RunSpec> expand_grid(const GridRequest& req) {
  if (req.seeds < 1 || req.seeds > kMaxSeeds)
    throw UsageError("--seeds must be from 1 to " + std::to_string(kMaxSeeds) + ", got " + std::to_string(req.seeds));
  if (req.budget < 1 || req.budget > kMaxBudget)
    throw UsageError("--budget must be from 1 to " + std::to_string(kMaxBudget) + ", got " +
                     std::to_string(req.budget));

  std::vector<std::string> envs = req.envs;
  std::vector<std::string> optimizers = req.optimizers;
  const bool envs_explicit = !envs.empty(), opts_explicit = !optimizers.empty();
  if (!req.all && (!envs_explicit || !opts_explicit))
    throw UsageError("nothing to run: give --all, or both --env and --optimizer");
  if (!envs_explicit) envs = grid_env_names();
  if (!opts_explicit)
    for (const auto& e : optimizer_entries()) optimizers.push_back(e.name);

  // --set's settings of an env of the grid are its options; the others must be optimizer knobs
  std::map<std::string, EnvOptions> env_options;
  std::map<std::string, KnobSettings> knobs;
  for (const auto& [owner, settings] : req.knobs) {
    if (std::find(envs.begin(), envs.end(), owner) != envs.end())
      env_options[owner] = settings;
    else
      knobs[owner] = settings;
  }

  // validate every name before anything runs; duplicates are a user error too. Each env is
  // resolved once: its one shared object (metadata: no model is built) and its config
  std::set<std::string> seen;
  std::vector<std::shared_ptr<const Env>> env_objects;
  std::vector<std::shared_ptr<const ResolvedConfig>> env_configs;
  for (const auto& name : envs) {
    if (!seen.insert("env:" + name).second) throw UsageError("env '" + name + "' given twice");
    const auto options = env_options.find(name);
    env_objects.push_back(shared_env(name, options == env_options.end() ? EnvOptions{} : options->second));
    env_configs.push_back(resolved_config(env_objects.back()->config()));
  }
  if (!(req.ext_timeout_s > 0.0 && req.ext_timeout_s <= 86400.0))
    throw UsageError("--ext-timeout must be from 0 to 86400 seconds, got " + std::to_string(req.ext_timeout_s));
  std::map<std::string, ExtOptimizerSpec> ext;           // by optimizer name, probed
  std::map<std::string, const OptimizerEntry*> entries;  // by optimizer name, the registry's
  for (const auto& name : optimizers) {
    if (!seen.insert("opt:" + name).second) throw UsageError("optimizer '" + name + "' given twice");
    if (const std::string ext_name = ext_name_of(name); !ext_name.empty()) {
      check_ext_name(ext_name);
      const auto command = req.ext.find(ext_name);
      if (command == req.ext.end())
        throw UsageError("optimizer '" + name + "' needs its command: --ext " + ext_name + "='COMMAND'");
      ext.emplace(name, ExtOptimizerSpec{ext_name, command->second, req.ext_timeout_s, "", ""});
      continue;
    }
    entries[name] = &optimizer_entry(name);
  }
  for (const auto& [name, command] : req.ext)
    if (!ext.count("ext:" + name))
      throw UsageError("--ext names 'ext:" + name + "', which is not in the grid's --optimizer list");
  std::map<std::string, std::shared_ptr<const ResolvedConfig>> opt_configs;  // by optimizer name
  for (const auto& [name, settings] : knobs) {
    if (!seen.count("opt:" + name))
      throw UsageError("--set names '" + name +
                       "', which is neither an env nor an optimizer of the grid "
                       "(--set ENV.KEY=VALUE, --set OPTIMIZER.KNOB=VALUE)");
    if (ext.count(name)) throw UsageError("optimizer '" + name + "' has no knobs to --set");
    // unknown knob, malformed or out-of-range value: UsageError
    opt_configs[name] = resolved_config(make_optimizer(name, settings)->config());
  }
  // the programs say who they are once, before anything runs (UsageError when one cannot)
  for (auto& [name, spec] : ext) {
    spec = ext_probe(std::move(spec));
    opt_configs[name] = resolved_config(make_ext_optimizer(spec)->config());
  }
  for (const auto& [name, entry] : entries)
    if (!opt_configs.count(name)) opt_configs[name] = resolved_config(entry->make()->config());

  std::vector<RunSpec> grid;
  const auto add_seeds = [&](std::size_t e, const std::string& opt, const KnobSettings& settings,
                             const std::optional<ExtOptimizerSpec>& program, const OptimizerEntry* entry) {
    const auto options = env_options.find(envs[e]);
    const ResultsVersions versions = current_results_versions(envs[e], opt);
    for (int s = 0; s < req.seeds; ++s) {
      RunSpec spec{envs[e],
                   opt,
                   s,
                   req.budget,
                   per_run_seed(envs[e], opt, s),
                   settings,
                   program,
                   options == env_options.end() ? EnvOptions{} : options->second};
      spec.resolved_env = env_objects[e];
      spec.entry = entry;
      spec.env_config = env_configs[e];
      spec.opt_config = opt_configs.at(opt);
      spec.versions = versions;
      grid.push_back(std::move(spec));
    }
  };
  for (std::size_t e = 0; e < envs.size(); ++e) {
    for (const auto& opt : optimizers) {
      if (const auto x = ext.find(opt); x != ext.end()) {
        add_seeds(e, opt, {}, x->second, nullptr);
        continue;
      }
      const OptimizerEntry& entry = *entries.at(opt);
      if (entry.needs_gradient && !env_objects[e]->differentiable()) {
        if (envs_explicit && opts_explicit)
          throw UsageError("optimizer '" + opt + "' needs gradients; env '" + envs[e] + "' is not differentiable");
        continue;
      }
      if (entry.needs_rl && !env_objects[e]->supports_rl()) {
        if (envs_explicit && opts_explicit)
          throw UsageError("optimizer '" + opt + "' needs an RL view; env '" + envs[e] +
                           "' has none (see `harness list`)");
        continue;
      }
      const auto k = knobs.find(opt);
      add_seeds(e, opt, k == knobs.end() ? KnobSettings{} : k->second, std::nullopt, &entry);
    }
  }
  return grid;
}

void parse_ext_setting(const std::string& text, std::map<std::string, std::string>& ext) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw UsageError("--ext wants NAME=COMMAND (e.g. my-opt='python3 opt.py'), got '" + text + "'");
  const std::string name = text.substr(0, eq);
  check_ext_name(name);
  if (!ext.emplace(name, text.substr(eq + 1)).second) throw UsageError("--ext " + name + " given twice");
}

namespace {

// "NAME.KNOB=VALUE" for the first registered optimizer with knobs (the harness names no optimizer)
std::string knob_example() {
  for (const auto& e : optimizer_entries())
    if (!e.knobs.empty()) return e.name + "." + e.knobs.front() + "=VALUE";
  return "OPTIMIZER.KNOB=VALUE";
}

}  // namespace

void parse_knob_setting(const std::string& text, std::map<std::string, KnobSettings>& knobs) {
  const auto dot = text.find('.');
  const auto eq = text.find('=');
  if (dot == std::string::npos || eq == std::string::npos || dot == 0 || eq < dot + 2 || eq + 1 == text.size())
    throw UsageError("--set wants OPTIMIZER.KNOB=VALUE or ENV.KEY=VALUE (e.g. " + knob_example() +
                     ", plb-pinch.target=Pinch3D-v1.npy), got '" + text + "'");
  const std::string opt = text.substr(0, dot), key = text.substr(dot + 1, eq - dot - 1);
  if (!knobs[opt].emplace(key, text.substr(eq + 1)).second)
    throw UsageError("--set " + opt + "." + key + " given twice");
}

EnvOptions parse_env_settings(const std::string& env, const std::vector<std::string>& settings) {
  std::map<std::string, KnobSettings> by_owner;
  for (const auto& text : settings) parse_knob_setting(text, by_owner);
  for (const auto& [owner, values] : by_owner)
    if (owner != env)
      throw UsageError("--set names '" + owner + "'; this command runs env '" + env + "' alone (its options: --set " +
                       env + ".KEY=VALUE)");
  return by_owner.count(env) ? by_owner.at(env) : EnvOptions{};
}

std::vector<std::string> settings_with_absolute_paths(const std::vector<std::string>& settings) {
  std::vector<std::string> out;
  for (const auto& text : settings) {
    std::map<std::string, KnobSettings> one;
    parse_knob_setting(text, one);
    const auto& [owner, values] = *one.begin();
    const auto& [key, value] = *values.begin();
    bool path = false;
    try {
      for (const auto& o : env_family_of(owner).options) path = path || (o.key == key && o.path);
    } catch (const UsageError&) {
      // not an env: an optimizer's knob
    }
    out.push_back(path ? owner + "." + key + "=" + std::filesystem::absolute(value).lexically_normal().string() : text);
  }
  return out;
}

}  // namespace dsb
