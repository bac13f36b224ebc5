#pragma once
// Test-only env for the RL optimizers: a point on a line must reach a target. Small enough that
// PPO and SAC learn it within a test's budget, and far enough from the start that random search
// does not: p_0 = 0, p_{t+1} = p_t + step a_t with a_t in [-1, 1], loss = |p_T - target|. The
// params are the T actions (loss(x) = the RL episode with actions x, bit for bit); the RL
// observation is (p_t, t / T), action repeat 1. With the defaults (T = 20, step 0.1, target 1)
// random actions end at p_T ~ N(0, 0.26^2), the target 3.9 standard deviations away, while
// holding a = 0.5 reaches it (to round-off).
#include <cmath>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "envs/core/env.hpp"

namespace dsb::testing {

struct ReachConfig {
  int steps = 20;
  double step = 0.1;
  double target = 1.0;
};

class ReachEnv : public Env {
 public:
  explicit ReachEnv(ReachConfig cfg = {}) : Env(info_of(cfg)), cfg_(cfg) {}
  nlohmann::json config() const override {
    return {{"steps", cfg_.steps}, {"step", cfg_.step}, {"target", cfg_.target}};
  }
  const ReachConfig& reach_config() const { return cfg_; }

  class Rl : public RlEnv {
   public:
    explicit Rl(const ReachEnv& env) : env_(env) {}
    int observation_dim() const override { return 2; }
    int action_dim() const override { return 1; }
    int horizon() const override { return env_.cfg_.steps; }
    int action_repeat() const override { return 1; }
    void reset() override { p_ = 0.0, t_ = 0; }
    std::vector<double> observe() const override { return {p_, static_cast<double>(t_) / horizon()}; }
    void step(std::span<const double> a) override {
      if (done()) throw std::logic_error("reach: step after the end");
      p_ += env_.cfg_.step * std::fmin(1.0, std::fmax(-1.0, a[0]));
      ++t_;
    }
    bool done() const override { return t_ >= horizon(); }
    double final_loss() const override { return std::fabs(p_ - env_.cfg_.target); }

   private:
    const ReachEnv& env_;
    double p_ = 0.0;
    int t_ = 0;
  };
  std::unique_ptr<RlEnv> make_rl() const override { return std::make_unique<Rl>(*this); }

 protected:
  double rollout(std::span<const double> x, Workspace&, ThreadTeam&) const override {
    Rl rl(*this);
    rl.reset();
    for (int t = 0; t < cfg_.steps; ++t) rl.step(x.subspan(t, 1));
    return rl.final_loss();
  }
  double rollout_with_grad(std::span<const double>, std::span<double>, Workspace&, ThreadTeam&) const override {
    throw std::logic_error("reach: no gradient");
  }

 private:
  static EnvInfo info_of(const ReachConfig& cfg) {
    EnvInfo info;
    info.name = "reach-test";
    info.dim = cfg.steps;
    info.differentiable = false;
    info.rl = true;
    info.cost_hint_s = 1e-6;
    return info;
  }
  ReachConfig cfg_;
};

}  // namespace dsb::testing
