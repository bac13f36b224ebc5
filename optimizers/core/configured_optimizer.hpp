#pragma once
// What every optimizer with a config struct shares: its name, whether it needs the gradient, and
// its config (checked once, when the optimizer is made; its JSON is what each run stores).
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "optimizers/core/optimizer.hpp"

namespace dsb {

// Config has to_json() and validate(), or validate(owner) for a config whose messages name the
// optimizer it belongs to (gd's and rand-descents' DescentConfig): that check throws ConfigError
// naming the field.
template <class Config>
class ConfiguredOptimizer : public Optimizer {
 public:
  const std::string& name() const override { return name_; }
  bool needs_gradient() const override { return needs_gradient_; }
  nlohmann::json config() const override { return cfg_.to_json(); }

 protected:
  ConfiguredOptimizer(std::string name, bool needs_gradient, Config cfg)
      : name_(std::move(name)), needs_gradient_(needs_gradient), cfg_(std::move(cfg)) {
    if constexpr (requires { cfg_.validate(); })
      cfg_.validate();
    else
      cfg_.validate(name_);
  }

  const std::string name_;
  const bool needs_gradient_;
  Config cfg_;
};

}  // namespace dsb
