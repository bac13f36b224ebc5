#pragma once
// Optimizers by name; one registration line each in optimizers/core/registry.cpp.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "optimizers/core/optimizer.hpp"

namespace dsb {

struct OptimizerEntry {
  std::string name;
  std::string description;
  bool needs_gradient;
  std::function<std::unique_ptr<Optimizer>()> make;
  bool needs_rl = false;  // drives the env's per-step view (Objective::rl_*): paired only with RL envs
};

const std::vector<OptimizerEntry>& optimizer_entries();

// Throws UsageError "unknown optimizer 'NAME'".
std::unique_ptr<Optimizer> make_optimizer(const std::string& name);
const OptimizerEntry& optimizer_entry(const std::string& name);

}  // namespace dsb
