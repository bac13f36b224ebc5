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
    // batches of kBatch points, drawn in the order one-at-a-time sampling would draw them (the
    // batch size changes no result, so it is not part of the config)
    constexpr std::size_t kBatch = 16;
    const std::size_t d = static_cast<std::size_t>(f.dim());
    std::vector<double> xs(kBatch * d), losses(kBatch);
    // until the budget wrapper throws BudgetExhausted
    for (;;) {
      for (auto& xi : xs) xi = rng.uniform(-1.0, 1.0);
      f.values(xs, losses);
    }
  }

 private:
  std::string name_ = "random";
};

}  // namespace

std::unique_ptr<Optimizer> make_random_search() { return std::make_unique<RandomSearch>(); }

}  // namespace dsb
