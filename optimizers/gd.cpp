#include "optimizers/gd.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "common/error.hpp"

namespace dsb {

void DescentConfig::validate(const std::string& owner) const {
  adam.validate(owner);
  if (max_steps < 0) throw ConfigError(owner, "max_steps", "must be >= 0");
  if (patience < 0) throw ConfigError(owner, "patience", "must be >= 0");
  if (!(min_improvement >= 0.0)) throw ConfigError(owner, "min_improvement", "must be >= 0");
}

nlohmann::json DescentConfig::to_json() const {
  return {{"adam", adam.to_json()},       {"random_starts", random_starts},
          {"max_steps", max_steps},       {"patience", patience},
          {"min_improvement", min_improvement}};
}

DescentConfig gd_defaults() { return DescentConfig{}; }

DescentConfig rand_descents_defaults() {
  DescentConfig c;
  c.random_starts = true;
  c.max_steps = 100;
  c.patience = 10;
  c.min_improvement = 1e-9;
  return c;
}

namespace {

class Descents : public Optimizer {
 public:
  Descents(std::string name, DescentConfig cfg) : name_(std::move(name)), cfg_(cfg) {
    cfg_.validate(name_);
  }
  const std::string& name() const override { return name_; }
  bool needs_gradient() const override { return true; }
  nlohmann::json config() const override { return cfg_.to_json(); }

  void minimize(Objective& f, Rng& rng) override {
    const int n = f.dim();
    std::vector<double> x(n), grad(n), best_x(n), best_grad(n);
    for (;;) {
      // start: box centre for gd, uniform random for rand-descents
      for (auto& xi : x) xi = cfg_.random_starts ? rng.uniform(-1.0, 1.0) : 0.0;
      descend(f, x, grad, best_x, best_grad);
      if (!cfg_.random_starts) return;  // only reached when the descent stops by itself
    }
  }

 private:
  void descend(Objective& f, std::vector<double>& x, std::vector<double>& grad,
               std::vector<double>& best_x, std::vector<double>& best_grad) {
    AdamConfig adam_cfg = cfg_.adam;
    Adam adam(adam_cfg, f.dim());
    double best = std::numeric_limits<double>::infinity();
    int stale = 0;
    for (int step = 0; cfg_.max_steps == 0 || step < cfg_.max_steps; ++step) {
      const double loss = f.value_and_grad(x, grad);
      if (!std::isfinite(loss)) {
        // failed episode: back to the best point, half the step size, fresh moments
        if (!std::isfinite(best)) return;  // nothing to go back to: give up this descent
        adam_cfg.lr *= 0.5;
        adam = Adam(adam_cfg, f.dim());
        x = best_x;
        adam.step(x, best_grad);
        continue;
      }
      if (!std::isfinite(best) || loss < best - cfg_.min_improvement * std::abs(best)) {
        stale = 0;
      } else if (cfg_.patience > 0 && ++stale >= cfg_.patience) {
        return;
      }
      if (loss < best) {
        best = loss;
        best_x = x;
        best_grad = grad;
      }
      adam.step(x, grad);
    }
  }

  std::string name_;
  DescentConfig cfg_;
};

}  // namespace

std::unique_ptr<Optimizer> make_gd(const DescentConfig& cfg) {
  return std::make_unique<Descents>("gd", cfg);
}

std::unique_ptr<Optimizer> make_rand_descents(const DescentConfig& cfg) {
  return std::make_unique<Descents>("rand-descents", cfg);
}

}  // namespace dsb
