#pragma once
// Exact Gaussian process regression for Bayesian optimization (Eigen, double):
// constant mean, Matern-5/2 kernel with one lengthscale per input dimension and an outputscale,
// Gaussian noise bounded below; priors as BoTorch's 2022 SingleTaskGP. Inputs are expected in the
// unit box [0, 1]^d; outputs are standardized internally (mean, unbiased std) at every refit and
// predictions are returned on the original scale.
#include <cstdint>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "common/rng.hpp"

namespace dsb {

struct GpConfig {
  // Gamma(concentration, rate) priors on the constrained values, as GPyTorch's GammaPrior
  double lengthscale_prior_concentration = 3.0, lengthscale_prior_rate = 6.0;
  double outputscale_prior_concentration = 2.0, outputscale_prior_rate = 0.15;
  double noise_prior_concentration = 1.1, noise_prior_rate = 0.05;
  double noise_floor = 1e-4;      // lower bound of the noise variance (standardized units)
  bool constant_mean = true;      // false: zero mean (on standardized outputs)
  int fit_attempts = 3;           // L-BFGS starts: current values, then draws from the priors
  int fit_max_evaluations = 200;  // per L-BFGS start
  double min_variance = 1e-10;    // predictive variance floor (standardized units)
  void validate() const;          // throws ConfigError naming the field
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(lengthscale_prior_concentration, lengthscale_prior_rate, outputscale_prior_concentration,
                    outputscale_prior_rate, noise_prior_concentration, noise_prior_rate, noise_floor, constant_mean,
                    fit_attempts, fit_max_evaluations, min_variance)
};

// What a hyperparameter fit starts from (GaussianProcess::begin_fit): per L-BFGS start, the
// optimized coordinates (clamped into the fit box) and the nlopt::srand seed drawn for it.
struct GpFitStarts {
  std::vector<std::vector<double>> x;
  std::vector<std::uint64_t> seeds;
};

// What a fit found (GaussianProcess::search_fit): the best theta (d + 3), empty when no start
// reached a finite objective, and the likelihood evaluations (fit_objective calls) it made. As
// a result of the optimizer's own work (optimizers/core/work_memo.hpp): {evaluations, found (1
// or 0), theta (d + 3, zeros when not found)}.
struct GpFitResult {
  Eigen::VectorXd theta;
  std::int64_t likelihood_evaluations = 0;
  static std::size_t payload_size(int dim) { return static_cast<std::size_t>(dim) + 5; }
  std::vector<double> payload(int dim) const;
  static GpFitResult from_payload(const std::vector<double>& payload, int dim);
};

struct GpHyperparameters {
  Eigen::VectorXd lengthscales;  // (d)
  double outputscale = 0.0;      // signal variance
  double noise = 0.0;            // noise variance
  double mean = 0.0;             // constant mean (standardized units; 0 with a zero mean)
};

class GaussianProcess {
 public:
  GaussianProcess(int dim, const GpConfig& cfg);

  int dim() const { return dim_; }
  int size() const;
  const GpHyperparameters& hyperparameters() const { return hyper_; }
  void set_hyperparameters(const GpHyperparameters& h);  // refactors the kernel matrix

  // Replaces the data: X (n x d) in [0,1]^d, y (n). Standardizes y, factors with the current
  // hyperparameters (GPyTorch's initial values before the first fit).
  void set_data(const Eigen::MatrixXd& X, const Eigen::VectorXd& y);

  // Adds one point, extending the Cholesky factor in O(n^2) with the current hyperparameters and
  // the standardization of the last refit (or set_data). Falls back to a full factorization with
  // jitter when the new diagonal is not positive. On an empty GP it acts as set_data.
  void add_point(const Eigen::VectorXd& x, double y);

  // Maximizes log marginal likelihood + log priors over log-parameters with NLopt's L-BFGS
  // (analytic gradient) from cfg.fit_attempts starts (the current values, then draws from the
  // priors) and keeps the best (BoTorch stops at the first success instead); re-standardizes y
  // and refactors. Jitter retries (1e-8, x10, up to 3 times, times the outputscale) when the
  // Cholesky factorization fails. rng draws: per start, the prior sample (not for the first),
  // then one nlopt::srand seed. Without data it does nothing.
  void fit(Rng& rng);
  // fit() in its three steps, so that the costly middle one can be skipped with a result
  // computed before (optimizers/core/work_memo.hpp): begin_fit standardizes and makes every draw
  // fit() makes; search_fit runs the L-BFGS starts (the cost: O(n^3) per evaluation); end_fit
  // takes the result, counts what the search counted (for a recalled one: its evaluations, as
  // search_fit would have; failures), re-seeds NLopt as the search did and refactors.
  GpFitStarts begin_fit(Rng& rng);
  GpFitResult search_fit(const GpFitStarts& starts);
  void end_fit(const GpFitStarts& starts, const GpFitResult& result, bool recalled);
  // a digest of the GP's whole state: its data (inputs, outputs), standardization,
  // hyperparameters and jitter; what fit() and the acquisition compute is a function of it
  std::uint64_t digest() const;
  // the key of a fit from `starts` in this state (digest() and the starts)
  std::uint64_t fit_key(const GpFitStarts& starts) const;
  // fit() calls so far in which no start reached a finite objective (the hyperparameters were kept)
  int fit_failures() const { return fit_failures_; }
  // what the fits cost: their likelihood evaluations (fit_objective calls), and the sum of n^3
  // over them (n the points at each: a Cholesky factorization and an inverse each)
  std::int64_t likelihood_evaluations() const { return likelihood_evaluations_; }
  double likelihood_n3() const { return likelihood_n3_; }
  // diagonal jitter of the current factor (0 when the plain Cholesky factorization worked)
  double jitter() const { return jitter_; }

  // Objective of the fit on the current (standardized) data at log-parameters
  // theta = (log lengthscales (d), log outputscale, log(noise - noise_floor), mean):
  // [log N(y | mean, K + noise I) + sum log priors] / n, and its gradient (size d + 3).
  double fit_objective(const Eigen::VectorXd& theta, Eigen::VectorXd* grad) const;
  Eigen::VectorXd theta_of(const GpHyperparameters& h) const;
  GpHyperparameters hyper_of(const Eigen::VectorXd& theta) const;

  // Posterior of the latent function at x (original output scale); the variance is floored.
  // With non-null gradients, also d mean / dx and d variance / dx (d); d variance is 0 where the
  // floor is active. Cost O(n d) for the mean, + n^2 / 2 for the variance (one triangular solve),
  // + n^2 / 2 for d variance (a second one). Without data: the prior.
  void predict(const Eigen::VectorXd& x, double* mean, double* variance, Eigen::VectorXd* dmean = nullptr,
               Eigen::VectorXd* dvariance = nullptr) const;

  // The lower Cholesky factor of K + noise I (n x n), for tests: an O(n^2) copy out of the
  // growable storage, refreshed by each call (so not safe to call from two threads at once).
  const Eigen::MatrixXd& cholesky() const;

  // Matern-5/2: k(r) = s (1 + sqrt5 r + 5/3 r^2) exp(-sqrt5 r), r^2 = sum ((a_i - b_i) / l_i)^2
  static double matern52(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const GpHyperparameters& h);

 private:
  int dim_;
  GpConfig cfg_;
  GpHyperparameters hyper_;
  // implementation state: data, standardization, factor, alpha
  Eigen::MatrixXd X_;              // (n x d)
  Eigen::MatrixXd Xs_;             // (d x n) inputs divided by the lengthscales, one point per column
  Eigen::VectorXd y_raw_, y_std_;  // (n) original and standardized outputs
  double y_mean_ = 0.0, y_scale_ = 1.0;
  // lower Cholesky factor of K + (noise + jitter) I: the top-left n x n block of Lbuf_, whose
  // spare capacity lets add_point grow it without moving the factor (only the lower part is kept)
  Eigen::MatrixXd Lbuf_;       // (capacity x capacity)
  mutable Eigen::MatrixXd L_;  // (n x n) copy made by cholesky(), upper part 0
  Eigen::VectorXd z_;          // L^-1 (y_std - mean) (n), extended in O(n) by add_point
  Eigen::VectorXd alpha_;      // (K + noise I)^-1 (y_std - mean) = L^-T z (n)
  double jitter_ = 0.0;        // diagonal jitter of the current factor (0 when the plain one worked)
  int n_ = 0;
  std::uint64_t inputs_digest_ = 0;  // FNV-1a over X_'s rows in order (set_data, add_point)
  int fit_failures_ = 0;
  mutable std::int64_t likelihood_evaluations_ = 0;
  mutable double likelihood_n3_ = 0.0;
  void standardize();                                                    // y_mean_, y_scale_, y_std_ from y_raw_
  void fit_box(std::vector<double>& lb, std::vector<double>& ub) const;  // the fit's box on theta
  void rescale_inputs();                                                 // Xs_ from X_ and the lengthscales
  void refactor();                       // factor, jitter_, z_, alpha_ from Xs_, y_std_ and hyper_ (jitter ladder)
  void reserve_factor(int n, int keep);  // capacity of Lbuf_ >= n, keeping the top-left keep x keep
};

}  // namespace dsb
