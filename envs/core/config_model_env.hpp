#pragma once
// What every simulated env holds: its validated config (cfg_) and the immutable model built from
// that config on first use (model_, lazy_model.hpp). ConfigModelEnv<Config, Model> keeps both,
// answers config() with the config's JSON (an env that adds to it overrides config()) and model();
// the env itself declares its rollouts, workspace and the rest of the Env interface.
#include <functional>
#include <utility>

#include <nlohmann/json.hpp>

#include "envs/core/env.hpp"
#include "envs/core/lazy_model.hpp"

namespace dsb {

template <class Config, class Model>
class ConfigModelEnv : public Env {
 public:
  nlohmann::json config() const override { return cfg_.to_json(); }
  const Model& model() const { return model_.get(); }

 protected:
  // keeps a copy of cfg (the env's info is made from cfg too, so it is not moved from); `build`
  // makes the model from the config, once, on the first model() call
  ConfigModelEnv(EnvInfo info, const Config& cfg, std::function<Model(const Config&)> build)
      : Env(std::move(info)), cfg_(cfg), model_([c = cfg_, build = std::move(build)] { return build(c); }) {}

  Config cfg_;
  LazyModel<Model> model_;
};

}  // namespace dsb
