#include "optimizers/core/registry.hpp"

#include "common/error.hpp"
#include "optimizers/cmaes.hpp"
#include "optimizers/gd.hpp"
#include "optimizers/random_search.hpp"

namespace dsb {

const std::vector<OptimizerEntry>& optimizer_entries() {
  // one registration line per optimizer
  static const std::vector<OptimizerEntry> entries = {
      {"random", "uniform random search in the box", false, [] { return make_random_search(); }},
      {"gd", "Adam from the box centre (lr 0.1), clipped to the box", true, [] { return make_gd(); }},
      {"rand-descents", "Adam descents restarted from uniform random starts", true,
       [] { return make_rand_descents(); }},
      {"cmaes", "CMA-ES (cmaes library rules) with IPOP restarts, sigma0 0.5", false,
       [] { return make_cmaes(); }},
  };
  return entries;
}

const OptimizerEntry& optimizer_entry(const std::string& name) {
  for (const auto& e : optimizer_entries())
    if (e.name == name) return e;
  throw UsageError("unknown optimizer '" + name + "' (see `harness list`)");
}

std::unique_ptr<Optimizer> make_optimizer(const std::string& name) {
  return optimizer_entry(name).make();
}

}  // namespace dsb
