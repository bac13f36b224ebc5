#pragma once
// `cmaes`: CMA-ES with active (negative) weights, following the rules of the CyberAgentAILab `cmaes`
// library (class CMA, v0.9.0 .. v0.13.1), with IPOP
// restarts (Auger & Hansen 2005) as in that repository's examples/ipop_cma.py. Re-implemented in
// Eigen from the published formulas; equation numbers refer to N. Hansen, "The CMA Evolution
// Strategy: A Tutorial" (arXiv 1604.00772).
//
// Where this follows the library exactly:
//   - constants (population, active weights with alpha_min, c1, cmu capped at 1 - c1 - 1e-8, c_sigma,
//     d_sigma, c_c, c_m = 1, chi_n), funhist_term = 10 + ceil(30 n / lambda);
//   - ask: one candidate per call, y = B diag(D) z, x = m + sigma y; resampled up to max_resampling
//     (100) times until inside [-1, 1]^n, then one more draw clipped to the box;
//   - tell: steps 1-10 of the reference, including the h_sigma exponent 2 (g + 1) taken after g was
//     incremented, the per-sample rescaling n / (|C^-1/2 y|^2 + 1e-8) of negative weights, and the
//     sigma cap 1e32 with no clip on the per-step change;
//   - should_stop: TolFun (history), TolX (sigma * C_ii, signed sigma * p_c), TolXUp (absolute),
//     NoEffectCoord, NoEffectAxis (axis g mod n), ConditionCov (on sqrt-eigenvalues), in this order;
//   - eigendecomposition once per generation (lazily at the first ask / should_stop after a tell),
//     after symmetrising C; negative eigenvalues -> 1e-8; C rebuilt as B diag(D^2) B^T.
//   - the mean is a copy (the pre-v0.9.0 "mutable mean" aliasing does not exist here).
// Where it deviates (none of these change a run in which the library itself would work):
//   - random numbers come from dsb::Rng (xoshiro256** + own polar normals), not numpy's
//     RandomState, so trajectories are not bit-comparable with Python (they would not be anyway:
//     eigenvector signs differ between LAPACK and Eigen);
//   - a NaN loss is treated as +infinity (worst); the library would sort it arbitrarily;
//   - should_stop() additionally reports CmaStop::numerical (checked first) when sigma, the mean or
//     C stopped being finite or the eigensolver failed, where the library would raise or propagate
//     NaN; with IPOP this restarts instead of crashing the run;
//   - the library's assertions (|mean| < 1e32, |x| < 1e32) are not needed: every told x lies in the
//     box and the new mean is a convex combination of told points (c_m = 1, positive weights sum
//     to 1), so it stays in the box too;
//   - IPOP: the library's example re-seeds with seed + 1 per restart; here the one run RNG stream
//     simply continues. The new mean is uniform in [-1, 1]^n, sigma is sigma0 again, the
//     population is multiplied by ipop_factor (rounded to the nearest integer).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "common/rng.hpp"
#include "optimizers/core/knobs.hpp"
#include "optimizers/core/configured_optimizer.hpp"
#include "optimizers/core/optimizer.hpp"

namespace dsb {

struct CmaesConfig {
  double sigma0 = 0.5;          // initial step size in the normalized box (chosen here)
  int population = 0;           // 0 = 4 + floor(3 ln n) (eq. 48); otherwise >= 2
  int max_resampling = 100;     // draws tried before the clip fallback (library default)
  bool ipop = true;             // restart with a larger population when should_stop() fires
  double ipop_factor = 2.0;     // population multiplier per restart
  double tolfun = 1e-12;        // TolFun (history) threshold
  double tolx_factor = 1e-12;   // tolx = tolx_factor * sigma0 (library: 1e-12 * sigma)
  double tolxup = 1e4;          // TolXUp: sigma * max(D) above this stops (absolute)
  double condition_max = 1e14;  // ConditionCov: max(D) / min(D) above this stops (D = sqrt eig)
  // throws ConfigError naming the field
  void validate() const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(sigma0, population, max_resampling, ipop, ipop_factor, tolfun, tolx_factor, tolxup, condition_max)
};

// Strategy constants for dimension n and population lambda, exactly by the library's formulas.
struct CmaesConstants {
  int lambda, mu;
  double mu_eff, c1, cmu, c_sigma, d_sigma, c_c, chi_n;
  int funhist_term;
  std::vector<double> weights;  // lambda weights: mu positive (sum 1), then zero/negative ones
  double mu_eff_minus = 0.0;    // variance-effective selection mass of the last lambda - mu weights
  double alpha_min = 0.0;       // sum of the negative weights is -alpha_min
};

// Default population 4 + floor(3 ln n) (eq. 48).
int cmaes_default_population(int n);
// Throws std::invalid_argument for n < 1 or lambda < 2.
CmaesConstants cmaes_constants(int n, int lambda);

// Which termination criterion fired (should_stop), in the library's order of checks.
enum class CmaStop { none, numerical, tolfun, tolx, tolxup, noeffectcoord, noeffectaxis, conditioncov };
const char* to_string(CmaStop s);

// One CMA-ES instance (the library's class CMA) on the box [-1, 1]^n.
class CmaState {
 public:
  // mean is copied; sigma > 0; lambda >= 2
  CmaState(const Eigen::VectorXd& mean, double sigma, int lambda, const CmaesConfig& cfg);

  int dim() const { return n_; }
  int population() const { return k_.lambda; }
  int generation() const { return g_; }
  const CmaesConstants& constants() const { return k_; }
  const Eigen::VectorXd& mean() const { return mean_; }
  double sigma() const { return sigma_; }
  const Eigen::MatrixXd& cov() const { return C_; }
  const Eigen::VectorXd& p_sigma() const { return p_sigma_; }
  const Eigen::VectorXd& p_c() const { return p_c_; }
  CmaStop stop_reason() const { return stop_; }

  // One candidate inside [-1, 1]^n (resample, then clip).
  Eigen::VectorXd ask(Rng& rng);
  // Exactly lambda (x, f) pairs, xs[k] with loss fs[k]; throws std::invalid_argument otherwise.
  // With `moved_mean` (BO-Leap), the mean moves there instead of to m + sigma <y>_w, and the
  // evolution paths see that actual step <y>_w = (moved_mean - m) / sigma (Hansen & Ostermeier
  // 2001, eqs. 14-17, driven by the realized mean shift); the rank-mu update still uses the sample.
  void tell(const std::vector<Eigen::VectorXd>& xs, const std::vector<double>& fs,
            const Eigen::VectorXd* moved_mean = nullptr);
  // The library's termination criteria; records which one fired in stop_reason().
  bool should_stop();

 private:
  // B, D of the current C (computed once per generation, cached until the next tell).
  bool eigen_decomposition();
  Eigen::VectorXd sample(Rng& rng) const;

  int n_;
  CmaesConstants k_;
  double tolfun_, tolx_, tolxup_, condition_max_;
  int max_resampling_;
  Eigen::VectorXd mean_;
  double sigma_;
  Eigen::MatrixXd C_;
  Eigen::VectorXd p_sigma_, p_c_;
  Eigen::MatrixXd B_;
  Eigen::VectorXd D_;
  bool have_eigen_ = false;
  bool eigen_failed_ = false;
  int g_ = 0;
  std::vector<double> funhist_;  // best and worst f of the last funhist_term generations
  CmaStop stop_ = CmaStop::none;
};

// What the last minimize() did (kept when it ends by BudgetExhausted).
struct CmaesRunStats {
  std::vector<int> populations;                    // lambda of each CMA-ES instance, in order (first = initial run)
  std::vector<CmaStop> stops;                      // why each finished instance stopped
  std::int64_t generations = 0;                    // generations told, over all instances
  std::vector<std::int64_t> instance_generations;  // generations told, per instance
  double final_sigma = 0.0;                        // sigma of the latest instance (sigma0 until its first tell)
  int restarts() const { return populations.empty() ? 0 : static_cast<int>(populations.size()) - 1; }
};

class Cmaes : public ConfiguredOptimizer<CmaesConfig> {
 public:
  explicit Cmaes(const CmaesConfig& cfg = {});
  // Runs until f throws BudgetExhausted (propagated); returns early only when ipop is false and the
  // single instance stops.
  void minimize(Objective& f, Rng& rng) override;
  const CmaesRunStats& last_run() const { return stats_; }
  // {"restarts", "generations", "final_sigma", "instances": [{"population", "generations",
  // "stop"}] (capped), "instances_truncated"}; the stop of an instance still running when the
  // budget ended is "budget".
  nlohmann::json diagnostics() const override;

 private:
  CmaesRunStats stats_;
};

std::unique_ptr<Optimizer> make_cmaes(const CmaesConfig& cfg = {});
// the fields `--set cmaes.KEY=VALUE` may set: sigma0, population, ipop (true/false), ipop_factor
KnobTable cmaes_knobs(CmaesConfig& cfg);
std::unique_ptr<Optimizer> make_cmaes_with(const KnobSettings& settings);

}  // namespace dsb
