#pragma once
// `bo`: exact-GP Bayesian optimization with LCB (beta = 1). A scrambled Sobol initial design,
// then one LCB minimizer per episode. Hyperparameters are refitted on a schedule that keeps
// 1,000 iterations affordable: after every new point while n <= refit_every_until, then whenever n
// has grown by refit_growth since the last fit; in between, each new point extends the Cholesky
// factor in O(n^2).
#include <memory>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "optimizers/bo/acquisition.hpp"
#include "optimizers/bo/gp.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/core/work_memo.hpp"

namespace dsb {

struct BoConfig {
  int initial_points = 0;      // 0 = clamp(d + 1, 5, 20) (chosen here)
  int refit_every_until = 50;  // refit after every point up to this many points
  double refit_growth = 0.1;   // then refit when n >= (1 + growth) n_last_fit
  LcbConfig lcb;
  GpConfig gp;
  void validate() const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(initial_points, refit_every_until, refit_growth, lcb, gp)
  int initial_points_for(int dim) const;
};

// Data of a GP-based optimizer in the normalized box, with the refit schedule. Failed episodes
// (+infinity) enter with the worst finite loss seen so far, so the model learns to avoid them.
// With a memo (the run's objective), every hyperparameter search and LCB argmin goes through it
// (optimizers/core/work_memo.hpp): a resumed run recalls them instead of computing them again,
// with the same draws from rng and the same counts, so nothing it does or reports changes.
class BoSurrogate {
 public:
  BoSurrogate(int dim, const BoConfig& cfg, WorkMemo* memo = nullptr);
  // adds (x in [-1,1]^d, loss); refits or extends per the schedule
  void add(const Eigen::VectorXd& x, double loss, Rng& rng, bool defer_fit = false);
  // refit on all data now
  void refit(Rng& rng);
  // LCB argmin, in [-1, 1]^d
  Eigen::VectorXd propose(Rng& rng);
  int size() const { return static_cast<int>(y_.size()); }
  int fits() const { return fits_; }
  // of fits() and of the proposals, those whose result the memo recalled (not in diagnostics():
  // a run's results are the same whether it was resumed or not)
  int fits_recalled() const { return fits_recalled_; }
  int proposals() const { return proposals_; }
  int proposals_recalled() const { return proposals_recalled_; }
  const GaussianProcess& gp() const { return gp_; }
  // {"points", "failed_points", "gp_fits", "gp_fit_failures", "jitter", "hyperparameters":
  // {"lengthscales" (unit-box inputs; capped), "lengthscales_truncated", "outputscale", "noise",
  // "mean" (standardized outputs)}}: the GP as it is now (after the latest fit or extension)
  nlohmann::json diagnostics() const;

 private:
  BoConfig cfg_;
  GaussianProcess gp_;
  std::vector<Eigen::VectorXd> u_;  // inputs in the unit box
  std::vector<double> y_;
  std::vector<int> failed_;  // indices whose loss was not finite
  WorkMemo* memo_;
  int last_fit_n_ = 0, fits_ = 0, factored_n_ = 0;
  int fits_recalled_ = 0, proposals_ = 0, proposals_recalled_ = 0;
  double worst_ = -std::numeric_limits<double>::infinity();
};

std::unique_ptr<Optimizer> make_bo(const BoConfig& cfg = {});

}  // namespace dsb
