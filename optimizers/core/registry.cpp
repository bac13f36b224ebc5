#include "optimizers/core/registry.hpp"

#include "common/error.hpp"
#include "optimizers/bo/bo.hpp"
#include "optimizers/boleap.hpp"
#include "optimizers/cmaes.hpp"
#include "optimizers/gd.hpp"
#include "optimizers/nlopt_adapters.hpp"
#include "optimizers/random_search.hpp"
#include "optimizers/rl/ppo.hpp"
#include "optimizers/rl/sac.hpp"

namespace dsb {
namespace {

// the knob names of a config, from its knob table over a default copy
template <class Config>
std::vector<std::string> knob_keys(KnobTable (*table)(Config&), Config cfg) {
  return table(cfg).keys();
}
template <class Config>
std::vector<std::string> knob_keys(KnobTable (*table)(const std::string&, Config&), const std::string& owner,
                                   Config cfg) {
  return table(owner, cfg).keys();
}

}  // namespace

const std::vector<OptimizerEntry>& optimizer_entries() {
  // one registration line per optimizer
  static const std::vector<OptimizerEntry> entries = {
      {"random", "uniform random search in the box", false, [] { return make_random_search(); }},
      {"gd", "Adam from the box centre (lr 0.1), clipped to the box", true, [] { return make_gd(); }, false,
       make_gd_with, knob_keys(descent_knobs, "gd", gd_defaults())},
      {"rand-descents", "Adam descents (lr 0.03) restarted from uniform random starts", true,
       [] { return make_rand_descents(); }, false, make_rand_descents_with,
       knob_keys(descent_knobs, "rand-descents", rand_descents_defaults())},
      {"cmaes", "CMA-ES (cmaes library rules) with IPOP restarts, sigma0 0.5", false,
       [] { return make_cmaes(); }, false, make_cmaes_with, knob_keys(cmaes_knobs, CmaesConfig{})},
      {"bo", "exact-GP Bayesian optimization (Matern-5/2 ARD, BoTorch-2022 priors), LCB beta 1", false,
       [] { return make_bo(); }},
      {"boleap", "BO-Leap (Alg. 1): LCB start, K=10 population (sigma 0.3), Adam descents (lr 0.03), CMA-ES update", true,
       [] { return make_boleap(); }, false, make_boleap_with, knob_keys(boleap_knobs, BoLeapConfig{})},
      {"nlopt-lbfgs", "NLopt LD_LBFGS (Luksan) from the centre, then random restarts", true,
       [] { return make_nlopt_lbfgs(); }},
      {"nlopt-bobyqa", "NLopt LN_BOBYQA (initial step 0.25), random restarts", false,
       [] { return make_nlopt_bobyqa(); }},
      {"nlopt-direct-l", "NLopt GN_DIRECT_L, restarts on random sub-boxes", false,
       [] { return make_nlopt_direct_l(); }},
      {"nlopt-crs2", "NLopt GN_CRS2_LM, restarts with a new random population", false,
       [] { return make_nlopt_crs2(); }},
      {"ppo", "PPO (Stable-Baselines3 defaults, 3 x 64 tanh MLPs), sparse reward -loss; RL envs only", false,
       [] { return make_ppo(); }, true},
      {"sac", "SB3 SAC defaults, 3x64 ReLU MLPs, sparse reward -loss at the last decision", false,
       [] { return make_sac(); }, true},
  };
  return entries;
}

const OptimizerEntry& optimizer_entry(const std::string& name) {
  for (const auto& e : optimizer_entries())
    if (e.name == name) return e;
  throw UsageError("unknown optimizer '" + name + "' (see `harness list`)");
}

std::unique_ptr<Optimizer> make_optimizer(const std::string& name, const KnobSettings& settings) {
  const OptimizerEntry& e = optimizer_entry(name);
  if (settings.empty()) return e.make();
  if (!e.make_with) throw UsageError("optimizer '" + name + "' has no knobs to --set");
  return e.make_with(settings);
}

}  // namespace dsb
