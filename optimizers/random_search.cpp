#include "optimizers/random_search.hpp"

#include <vector>

namespace dsb {
namespace {

class RandomSearch : public Optimizer {
 public:
  const std::string& name() const override { return name_; }
  bool needs_gradient() const override { return false; }
  nlohmann::json config() const override { return {{"sampler", "uniform in [-1,1]^d"}}; }
  void minimize(Objective& f, Rng& rng) override {
    std::vector<double> x(f.dim());
    // until the budget wrapper throws BudgetExhausted
    for (;;) {
      for (auto& xi : x) xi = rng.uniform(-1.0, 1.0);
      f.value(x);
    }
  }

 private:
  std::string name_ = "random";
};

}  // namespace

std::unique_ptr<Optimizer> make_random_search() { return std::make_unique<RandomSearch>(); }

}  // namespace dsb
