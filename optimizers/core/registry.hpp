#pragma once
// Optimizers by name; one registration line each in optimizers/core/registry.cpp.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "optimizers/core/knobs.hpp"
#include "optimizers/core/optimizer.hpp"

namespace dsb {

struct OptimizerEntry {
  std::string name;
  std::string description;
  bool needs_gradient;
  std::function<std::unique_ptr<Optimizer>()> make;
  bool needs_rl = false;  // drives the env's per-step view (Objective::rl_*): paired only with RL envs
  // made with knobs set (`--set NAME.KEY=VALUE`); empty for an optimizer without knobs
  std::function<std::unique_ptr<Optimizer>(const KnobSettings&)> make_with = {};
  std::vector<std::string> knobs = {};  // the keys make_with accepts
};

const std::vector<OptimizerEntry>& optimizer_entries();

// Throws UsageError "unknown optimizer 'NAME'"; with settings, also for an unknown knob, a
// malformed value, or an optimizer without knobs; ConfigError for a value out of range.
std::unique_ptr<Optimizer> make_optimizer(const std::string& name, const KnobSettings& settings = {});
const OptimizerEntry& optimizer_entry(const std::string& name);

}  // namespace dsb
