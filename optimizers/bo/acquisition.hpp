#pragma once
// Lower confidence bound LCB(u) = mu(u) - sqrt(beta) sigma(u) of a GP over the unit box, and its
// minimization: scrambled Sobol raw samples, the best few refined by L-BFGS (NLopt LD_LBFGS) with
// the analytic LCB gradient, the best refined point returned.
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "common/rng.hpp"
#include "optimizers/bo/gp.hpp"
#include "optimizers/bo/sobol.hpp"

namespace dsb {

struct LcbConfig {
  double beta = 1.0;         // LCB exploration weight: alpha = sqrt(beta) = 1 (paper)
  int raw_samples = 512;     // Sobol points scored before refinement (BoTorch tutorials: 512)
  int restarts = 5;          // best raw samples refined by L-BFGS (chosen here; tutorials: 10)
  int max_evaluations = 60;  // L-BFGS evaluations per restart (chosen here)
  void validate(const std::string& owner) const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(beta, raw_samples, restarts, max_evaluations)
};

// LCB value at u (unit box) and, when grad is non-null, its gradient (d)
double lcb(const GaussianProcess& gp, double beta, const Eigen::VectorXd& u, Eigen::VectorXd* grad);

// argmin of LCB over [0, 1]^d; the Sobol scramble is drawn from rng
Eigen::VectorXd minimize_lcb(const GaussianProcess& gp, const LcbConfig& cfg, Rng& rng);
// the same with the raw samples from `raw` (a scrambled sequence of gp.dim() dimensions, unused
// so far): what the rng overload does after drawing the scramble
Eigen::VectorXd minimize_lcb(const GaussianProcess& gp, const LcbConfig& cfg, SobolSequence& raw);
// the key of that argmin (optimizers/core/work_memo.hpp): the GP's state, the config, the scramble
std::uint64_t lcb_argmin_key(const GaussianProcess& gp, const LcbConfig& cfg, const SobolSequence& raw);

}  // namespace dsb
