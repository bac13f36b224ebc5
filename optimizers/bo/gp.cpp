// Exact GP regression (Matern-5/2 ARD, constant mean, Gaussian noise with a floor) with BoTorch's
// 2022 SingleTaskGP priors. Relies on: GPyTorch's
// defaults, psd_safe_cholesky and min_variance; limbo's O(n^2) Cholesky extension; NLopt's
// LD_LBFGS.
//
// Choices made here (and why):
// - Fit: every one of cfg.fit_attempts L-BFGS starts is run (the current hyperparameters, then
//   draws from the priors) and the BEST final objective is kept. BoTorch stops at the first start
//   that succeeds; best-of-N never does worse on the objective and is as deterministic.
// - Fit box on theta: log lengthscale and log outputscale in [ln 1e-3, ln 1e3] and
//   [ln 1e-4, ln 1e4]; log(noise - floor) in [ln 1e-12, ln 1e3] (so noise reaches the floor up
//   to 1e-12); constant mean in [-100, 100] (standardized units). Starts are clamped into the box.
// - Jitter: when the plain Cholesky fails, 1e-8, 1e-7, 1e-6 times the outputscale is added to the
//   diagonal (psd_safe_cholesky's absolute 1e-8 x10 ladder, made relative to the signal scale).
// - The gradient of the fit objective needs K^-1; it is formed from the factor by an in-place
//   triangular inverse and an L^-T L^-1 product, both recursive (blocked) so that each costs
//   n^3/3 flops, as LAPACK's trtri and lauum do.
#include "optimizers/bo/gp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <nlopt.hpp>

#include "common/config_fields.hpp"
#include "common/det_math.hpp"
#include "common/field_check.hpp"
#include "common/number_text.hpp"
#include "optimizers/bo/gp_pairs.hpp"
#include "optimizers/core/work_memo.hpp"

namespace dsb {

namespace {

constexpr double kSqrt5 = 2.23606797749978969641;
constexpr double kLog2Pi = 1.83787706640934548356;
constexpr double kFailedObjective = -1e10;  // fit objective when no factorization succeeds
constexpr int kJitterTries = 3;             // 1e-8, 1e-7, 1e-6 (times the outputscale)
constexpr double kJitterBase = 1e-8;
constexpr int kBlock = 48;  // base size of the recursive triangular kernels

// fit box on theta (see the file comment)
constexpr double kLogLengthscaleMin = -6.907755278982137, kLogLengthscaleMax = 6.907755278982137;
constexpr double kLogOutputscaleMin = -9.210340371976182, kLogOutputscaleMax = 9.210340371976182;
constexpr double kLogNoiseExcessMin = -27.631021115928547, kLogNoiseExcessMax = 6.907755278982137;
constexpr double kMeanBound = 100.0;

// Matern-5/2 from r^2: value, and gneg = -(dk/dr) / r = 5/3 s (1 + sqrt5 r) exp(-sqrt5 r)
inline double matern_r2(double s, double r2, double* gneg) {
  const double r = std::sqrt(r2);
  const double e = dm::exp(-kSqrt5 * r);
  if (gneg) *gneg = (5.0 / 3.0) * s * (1.0 + kSqrt5 * r) * e;
  return s * (1.0 + kSqrt5 * r + (5.0 / 3.0) * r2) * e;
}

inline double sqdist(const double* a, const double* b, int d) {
  double r2 = 0.0;
  for (int i = 0; i < d; ++i) {
    const double t = a[i] - b[i];
    r2 += t * t;
  }
  return r2;
}

// scratch vector of at least n doubles, reused by the calling thread (no allocation once grown)
double* scratch(std::vector<double>& v, std::size_t n) {
  if (v.size() < n) v.resize(n);
  return v.data();
}

// the inputs divided by the lengthscales, one column per dimension: Xt (n x d) from X (n x d)
Eigen::MatrixXd scaled_columns(const Eigen::MatrixXd& X, const Eigen::VectorXd& lengthscales) {
  Eigen::MatrixXd Xt(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < X.cols(); ++i) Xt.col(i) = X.col(i) / lengthscales[i];
  return Xt;
}

// strict lower triangle of K (n x n) from the scaled inputs Xt (n x d): the pairs' squared
// distances (gp_pairs), then k(r) per pair as matern_r2 computes it, the exps in batches of a
// column (dm::exp_batch gives dm::exp's bits); with G, also gneg per pair in G's strict lower part
void kernel_lower(const Eigen::MatrixXd& Xt, double s, Eigen::MatrixXd& K, Eigen::MatrixXd* G) {
  const int n = static_cast<int>(Xt.rows()), d = static_cast<int>(Xt.cols());
  K.resize(n, n);
  if (G) G->resize(n, n);
  gp_pairs::squared_distances(Xt.data(), n, d, K.data(), gp_pairs::default_path());
  thread_local std::vector<double> buf_r, buf_e;
  double* r = scratch(buf_r, static_cast<std::size_t>(n));
  double* e = scratch(buf_e, static_cast<std::size_t>(n));
  for (int b = 0; b + 1 < n; ++b) {
    const int m = n - b - 1;
    double* r2 = K.col(b).data() + b + 1;  // (m) squared distances, then kernel values
    for (int k = 0; k < m; ++k) {
      r[k] = std::sqrt(r2[k]);
      e[k] = -kSqrt5 * r[k];
    }
    dm::exp_batch(e, e, static_cast<std::size_t>(m));
    if (G) {
      double* g = G->col(b).data() + b + 1;
      for (int k = 0; k < m; ++k) g[k] = (5.0 / 3.0) * s * (1.0 + kSqrt5 * r[k]) * e[k];
    }
    for (int k = 0; k < m; ++k) r2[k] = s * (1.0 + kSqrt5 * r[k] + (5.0 / 3.0) * r2[k]) * e[k];
  }
}

bool factor_ok(const Eigen::Ref<Eigen::MatrixXd>& L) {
  for (Eigen::Index i = 0; i < L.rows(); ++i)
    if (!(L(i, i) > 0.0) || !std::isfinite(L(i, i))) return false;
  return true;
}

// Cholesky of K + noise I in place in A (n x n) with the jitter ladder: plain, then + 1e-8 s,
// 1e-7 s, 1e-6 s on the diagonal; K's strict lower triangle holds the kernel (kernel_lower).
// Returns the jitter used, or NaN when every try failed (A then holds garbage).
double factor_with_jitter(const Eigen::MatrixXd& K, double s, double noise, Eigen::Ref<Eigen::MatrixXd> A) {
  double jitter = 0.0;
  for (int k = 0; k <= kJitterTries; ++k) {
    jitter = k == 0 ? 0.0 : kJitterBase * dm::pow(10.0, k - 1) * s;
    A.triangularView<Eigen::StrictlyLower>() = K;
    A.diagonal().setConstant(s + (noise + jitter));
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(A);
    if (llt.info() == Eigen::Success && factor_ok(A)) return jitter;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// in-place inverse of the lower triangular A (lower part only; LAPACK trti2 order)
void trtri_lower_unblocked(Eigen::Ref<Eigen::MatrixXd> A) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    A(j, j) = 1.0 / A(j, j);
    const double ajj = -A(j, j);
    // x = A(j+1:, j) <- ajj * inv(A(j+1:, j+1:)) x, bottom up so that x_k (k < i) is still old
    for (Eigen::Index i = n - 1; i > j; --i) {
      double t = 0.0;
      for (Eigen::Index k = j + 1; k <= i; ++k) t += A(i, k) * A(k, j);
      A(i, j) = ajj * t;
    }
  }
}

// The recursion of the blocked triangular kernels on A (n x n) = [P 0; Q R], P of n / 2 rows:
// unblocked(A) at kBlock rows or fewer, else halves(P, Q, R) (views into A)
template <class Unblocked, class Halves>
void on_halves(Eigen::Ref<Eigen::MatrixXd> A, Unblocked unblocked, Halves halves) {
  const Eigen::Index n = A.rows();
  if (n <= kBlock) return unblocked(A);
  const Eigen::Index n1 = n / 2, n2 = n - n1;
  halves(A.topLeftCorner(n1, n1), A.bottomLeftCorner(n2, n1), A.bottomRightCorner(n2, n2));
}

// in-place inverse of the lower triangular A: [P 0; Q R]^-1 = [P^-1 0; -R^-1 Q P^-1, R^-1]
void trtri_lower(Eigen::Ref<Eigen::MatrixXd> A) {
  on_halves(A, trtri_lower_unblocked, [](auto P, auto Q, auto R) {
    trtri_lower(P);
    Q = Q * P.template triangularView<Eigen::Lower>();          // Q P^-1
    R.template triangularView<Eigen::Lower>().solveInPlace(Q);  // R^-1 Q P^-1
    Q = -Q;
    trtri_lower(R);
  });
}

// lower triangle of M^T M in place, M lower triangular (LAPACK lauu2 order)
void lauum_lower_unblocked(Eigen::Ref<Eigen::MatrixXd> A) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index i = 0; i < n; ++i) {
    const double aii = A(i, i);
    double diag = 0.0;
    for (Eigen::Index k = i; k < n; ++k) diag += A(k, i) * A(k, i);
    // row i left of the diagonal: aii A(i, j) + sum_{k > i} A(k, i) A(k, j), rows below still old
    for (Eigen::Index j = 0; j < i; ++j) {
      double t = aii * A(i, j);
      for (Eigen::Index k = i + 1; k < n; ++k) t += A(k, i) * A(k, j);
      A(i, j) = t;
    }
    A(i, i) = diag;
  }
}

// [P 0; Q R]^T [P 0; Q R] = [P^T P + Q^T Q, .; R^T Q, R^T R]  (lower triangle)
void lauum_lower(Eigen::Ref<Eigen::MatrixXd> A) {
  on_halves(A, lauum_lower_unblocked, [](auto P, auto Q, auto R) {
    lauum_lower(P);
    P.template selfadjointView<Eigen::Lower>().rankUpdate(Q.transpose());
    Q = R.template triangularView<Eigen::Lower>().transpose() * Q;
    lauum_lower(R);
  });
}

// log of the Gamma(x; k, rate) density and its derivative with respect to log x
inline double log_gamma_density(double x, double k, double rate, double* dlogx) {
  if (dlogx) *dlogx = (k - 1.0) - rate * x;
  return k * dm::log(rate) + (k - 1.0) * dm::log(x) - rate * x - dm::lgamma(k);
}

// Gamma(k, rate) draw: Marsaglia and Tsang (2000), boosted by U^(1/k) for k < 1
double sample_gamma(Rng& rng, double k, double rate) {
  double boost = 1.0;
  if (k < 1.0) {
    boost = dm::pow(rng.uniform(), 1.0 / k);
    k += 1.0;
  }
  const double dd = k - 1.0 / 3.0, c = 1.0 / std::sqrt(9.0 * dd);
  for (;;) {
    const double x = rng.normal();
    double v = 1.0 + c * x;
    if (v <= 0.0) continue;
    v = v * v * v;
    const double u = rng.uniform();
    if (u < 1.0 - 0.0331 * (x * x) * (x * x)) return boost * dd * v / rate;
    if (dm::log(u) < 0.5 * x * x + dd * (1.0 - v + dm::log(v))) return boost * dd * v / rate;
  }
}

struct FitProblem {
  const GaussianProcess* gp;
  int full;  // d + 3
};

// negative fit objective on the optimized coordinates (theta without the mean for a zero mean)
double neg_objective(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  const auto* p = static_cast<const FitProblem*>(data);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(p->full);
  for (std::size_t i = 0; i < x.size(); ++i) theta[static_cast<Eigen::Index>(i)] = x[i];
  Eigen::VectorXd g;
  const double v = p->gp->fit_objective(theta, grad.empty() ? nullptr : &g);
  if (!std::isfinite(v) || (!grad.empty() && !g.allFinite())) {
    for (double& gi : grad) gi = 0.0;
    return -kFailedObjective;
  }
  for (std::size_t i = 0; i < grad.size(); ++i) grad[i] = -g[static_cast<Eigen::Index>(i)];
  return -v;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// config

void GpConfig::validate() const {
  const FieldCheck check("gp");
  check.number_above("lengthscale_prior_concentration", lengthscale_prior_concentration, 0.0);
  check.number_above("lengthscale_prior_rate", lengthscale_prior_rate, 0.0);
  check.number_above("outputscale_prior_concentration", outputscale_prior_concentration, 0.0);
  check.number_above("outputscale_prior_rate", outputscale_prior_rate, 0.0);
  check.number_above("noise_prior_concentration", noise_prior_concentration, 0.0);
  check.number_above("noise_prior_rate", noise_prior_rate, 0.0);
  check.number_at_least("noise_floor", noise_floor, 0.0);
  check.require(fit_attempts >= 1, "fit_attempts", "must be >= 1 (got " + std::to_string(fit_attempts) + ")");
  check.require(fit_max_evaluations >= 1, "fit_max_evaluations",
                "must be >= 1 (got " + std::to_string(fit_max_evaluations) + ")");
  check.number_at_least("min_variance", min_variance, 0.0);
}

nlohmann::json GpConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["kernel"] = "matern52_ard";
  return j;
}

// ---------------------------------------------------------------------------------------------
// construction, data

GaussianProcess::GaussianProcess(int dim, const GpConfig& cfg) : dim_(dim), cfg_(cfg) {
  if (dim < 1) throw std::invalid_argument("gp: dimension must be >= 1 (got " + std::to_string(dim) + ")");
  cfg_.validate();
  // GPyTorch's initial values: softplus(0) = ln 2 for lengthscales and outputscale, noise at the
  // prior mode 2.0 (not below the floor), mean 0
  hyper_.lengthscales = Eigen::VectorXd::Constant(dim, dm::log(2.0));
  hyper_.outputscale = dm::log(2.0);
  hyper_.noise = std::max(2.0, cfg_.noise_floor);
  hyper_.mean = 0.0;
  X_.resize(0, dim);
  Xs_.resize(dim, 0);
}

int GaussianProcess::size() const { return n_; }

const Eigen::MatrixXd& GaussianProcess::cholesky() const {
  L_ = Lbuf_.topLeftCorner(n_, n_).triangularView<Eigen::Lower>();
  return L_;
}

void GaussianProcess::reserve_factor(int n, int keep) {
  const Eigen::Index cap = Lbuf_.rows();
  if (cap >= n) return;
  const Eigen::Index grown = std::max<Eigen::Index>(n, cap + cap / 2 + 16);  // x1.5: amortized O(n^2)
  if (keep > 0) {
    Eigen::MatrixXd bigger(grown, grown);
    bigger.topLeftCorner(keep, keep).triangularView<Eigen::Lower>() = Lbuf_.topLeftCorner(keep, keep);
    Lbuf_.swap(bigger);
  } else {
    Lbuf_.resize(grown, grown);
  }
}

double GaussianProcess::matern52(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const GpHyperparameters& h) {
  double r2 = 0.0;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    const double t = (a[i] - b[i]) / h.lengthscales[i];
    r2 += t * t;
  }
  return matern_r2(h.outputscale, r2, nullptr);
}

void GaussianProcess::set_hyperparameters(const GpHyperparameters& h) {
  if (h.lengthscales.size() != dim_)
    throw std::invalid_argument("gp: " + std::to_string(h.lengthscales.size()) + " lengthscales for dimension " +
                                std::to_string(dim_));
  for (Eigen::Index i = 0; i < h.lengthscales.size(); ++i)
    if (!(h.lengthscales[i] > 0.0) || !std::isfinite(h.lengthscales[i]))
      throw std::invalid_argument("gp: lengthscale " + std::to_string(i) + " must be finite and > 0");
  if (!(h.outputscale > 0.0) || !std::isfinite(h.outputscale))
    throw std::invalid_argument("gp: outputscale must be finite and > 0");
  if (!(h.noise >= cfg_.noise_floor) || !std::isfinite(h.noise))
    throw std::invalid_argument("gp: noise must be finite and >= noise_floor " + number_text(cfg_.noise_floor));
  if (!std::isfinite(h.mean)) throw std::invalid_argument("gp: mean must be finite");
  hyper_ = h;
  if (!cfg_.constant_mean) hyper_.mean = 0.0;
  rescale_inputs();
  refactor();
}

void GaussianProcess::set_data(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) {
  if (X.cols() != dim_ || X.rows() != y.size())
    throw std::invalid_argument("gp: set_data needs X (n x " + std::to_string(dim_) + ") and y (n); got X " +
                                std::to_string(X.rows()) + " x " + std::to_string(X.cols()) + ", y " +
                                std::to_string(y.size()));
  if (!X.allFinite() || !y.allFinite()) throw std::invalid_argument("gp: set_data with non-finite values");
  X_ = X;
  y_raw_ = y;
  n_ = static_cast<int>(y.size());
  inputs_digest_ = kWorkKeyStart;
  for (int i = 0; i < n_; ++i) {
    const Eigen::VectorXd row = X_.row(i).transpose();
    inputs_digest_ = work_key(inputs_digest_, std::span<const double>(row.data(), static_cast<std::size_t>(dim_)));
  }
  standardize();
  rescale_inputs();
  refactor();
}

void GaussianProcess::standardize() {
  const int n = n_;
  y_mean_ = n > 0 ? y_raw_.mean() : 0.0;
  double sd = 1.0;
  if (n > 1) sd = std::sqrt((y_raw_.array() - y_mean_).square().sum() / (n - 1));
  y_scale_ = sd < 1e-8 ? 1.0 : sd;  // Standardize: below 1e-8 only de-mean
  y_std_ = (y_raw_.array() - y_mean_) / y_scale_;
}

void GaussianProcess::rescale_inputs() {
  Xs_.resize(dim_, n_);
  for (int i = 0; i < n_; ++i) Xs_.col(i) = X_.row(i).transpose().cwiseQuotient(hyper_.lengthscales);
}

void GaussianProcess::refactor() {
  const int n = n_;
  jitter_ = 0.0;
  if (n == 0) {
    z_.resize(0);
    alpha_.resize(0);
    return;
  }
  // exact size when the storage has to grow: a refit of n points need not pay for spare room
  if (Lbuf_.rows() < n) Lbuf_.resize(n, n);
  auto L = Lbuf_.topLeftCorner(n, n);
  Eigen::MatrixXd K;  // (n x n) strict lower triangle
  kernel_lower(scaled_columns(X_, hyper_.lengthscales), hyper_.outputscale, K, nullptr);
  jitter_ = factor_with_jitter(K, hyper_.outputscale, hyper_.noise, L);
  if (std::isnan(jitter_))
    throw std::runtime_error(
        "gp: Cholesky factorization of the kernel matrix failed with jitter up to 1e-6 x "
        "outputscale (n = " +
        std::to_string(n) + ")");
  z_ = y_std_.array() - hyper_.mean;
  L.triangularView<Eigen::Lower>().solveInPlace(z_);
  alpha_ = z_;
  L.triangularView<Eigen::Lower>().transpose().solveInPlace(alpha_);
}

void GaussianProcess::add_point(const Eigen::VectorXd& x, double y) {
  if (x.size() != dim_)
    throw std::invalid_argument("gp: add_point with " + std::to_string(x.size()) + " coordinates for dimension " +
                                std::to_string(dim_));
  if (!x.allFinite() || !std::isfinite(y)) throw std::invalid_argument("gp: add_point with non-finite values");
  if (n_ == 0) {  // no standardization to keep yet: behaves as set_data with one point
    set_data(x.transpose(), Eigen::VectorXd::Constant(1, y));
    return;
  }
  const int n = n_, d = dim_;
  const double s = hyper_.outputscale;
  // new column of K, then l = L^-1 k(X, x) by forward substitution: O(n d + n^2 / 2)
  const Eigen::VectorXd xs = x.cwiseQuotient(hyper_.lengthscales);
  Eigen::VectorXd l(n);
  for (int i = 0; i < n; ++i) l[i] = matern_r2(s, sqdist(Xs_.col(i).data(), xs.data(), d), nullptr);
  Lbuf_.topLeftCorner(n, n).triangularView<Eigen::Lower>().solveInPlace(l);
  const double d2 = s + hyper_.noise + jitter_ - l.squaredNorm();

  // append the data; y standardized with the frozen mean and scale
  inputs_digest_ = work_key(inputs_digest_, std::span<const double>(x.data(), static_cast<std::size_t>(d)));
  X_.conservativeResize(n + 1, Eigen::NoChange);
  X_.row(n) = x.transpose();
  Xs_.conservativeResize(Eigen::NoChange, n + 1);
  Xs_.col(n) = xs;
  y_raw_.conservativeResize(n + 1);
  y_raw_[n] = y;
  y_std_.conservativeResize(n + 1);
  y_std_[n] = (y - y_mean_) / y_scale_;
  n_ = n + 1;

  if (!(d2 > 0.0) || !std::isfinite(d2)) {  // lost positive definiteness: full factor with jitter
    refactor();
    return;
  }
  reserve_factor(n + 1, n);
  Lbuf_.row(n).head(n) = l.transpose();
  Lbuf_(n, n) = std::sqrt(d2);
  // z extends in O(n); alpha = L^-T z needs one backward substitution
  z_.conservativeResize(n + 1);
  z_[n] = (y_std_[n] - hyper_.mean - l.dot(z_.head(n))) / Lbuf_(n, n);
  alpha_ = z_;
  Lbuf_.topLeftCorner(n + 1, n + 1).triangularView<Eigen::Lower>().transpose().solveInPlace(alpha_);
}

// ---------------------------------------------------------------------------------------------
// hyperparameter fit

Eigen::VectorXd GaussianProcess::theta_of(const GpHyperparameters& h) const {
  Eigen::VectorXd t(dim_ + 3);
  t.head(dim_) = h.lengthscales.unaryExpr([](double v) { return dm::log(v); });
  t[dim_] = dm::log(h.outputscale);
  t[dim_ + 1] = dm::log(std::max(h.noise - cfg_.noise_floor, 0.0));  // -inf at the floor
  t[dim_ + 2] = cfg_.constant_mean ? h.mean : 0.0;
  return t;
}

GpHyperparameters GaussianProcess::hyper_of(const Eigen::VectorXd& theta) const {
  GpHyperparameters h;
  h.lengthscales = theta.head(dim_).unaryExpr([](double v) { return dm::exp(v); });
  h.outputscale = dm::exp(theta[dim_]);
  h.noise = cfg_.noise_floor + dm::exp(theta[dim_ + 1]);
  h.mean = cfg_.constant_mean ? theta[dim_ + 2] : 0.0;
  return h;
}

double GaussianProcess::fit_objective(const Eigen::VectorXd& theta, Eigen::VectorXd* grad) const {
  const int d = dim_, n = n_;
  if (theta.size() != d + 3)
    throw std::invalid_argument("gp: fit_objective needs theta of size d + 3 = " + std::to_string(d + 3));
  const GpHyperparameters h = hyper_of(theta);
  const double s = h.outputscale, noise = h.noise, m = h.mean;
  ++likelihood_evaluations_;
  likelihood_n3_ += static_cast<double>(n) * n * n;

  // log priors on the constrained values, gradients in theta coordinates
  Eigen::VectorXd g = Eigen::VectorXd::Zero(d + 3);
  double value = 0.0;
  for (int i = 0; i < d; ++i)
    value +=
        log_gamma_density(h.lengthscales[i], cfg_.lengthscale_prior_concentration, cfg_.lengthscale_prior_rate, &g[i]);
  value += log_gamma_density(s, cfg_.outputscale_prior_concentration, cfg_.outputscale_prior_rate, &g[d]);
  {
    const double k = cfg_.noise_prior_concentration, rate = cfg_.noise_prior_rate;
    value += log_gamma_density(noise, k, rate, nullptr);
    g[d + 1] = (noise - cfg_.noise_floor) * ((k - 1.0) / noise - rate);
  }
  if (n == 0) {
    if (grad) *grad = g;
    return value;
  }

  // factor K + noise I at theta (jitter ladder as in refactor)
  const Eigen::MatrixXd Xt = scaled_columns(X_, h.lengthscales);  // (n x d)
  Eigen::MatrixXd K, G;  // (n x n) strict lower triangles: k per pair; gneg, then w gneg, per pair
  kernel_lower(Xt, s, K, grad ? &G : nullptr);
  Eigen::MatrixXd A(n, n);  // L, then L^-1, then K^-1 in the lower triangle
  const double jitter = factor_with_jitter(K, s, noise, A);
  if (std::isnan(jitter)) {
    if (grad) *grad = Eigen::VectorXd::Zero(d + 3);
    return kFailedObjective;
  }
  Eigen::VectorXd alpha = y_std_.array() - m;
  A.triangularView<Eigen::Lower>().solveInPlace(alpha);
  const double quad = alpha.squaredNorm();
  double logdet = 0.0;
  for (int i = 0; i < n; ++i) logdet += dm::log(A(i, i));
  logdet *= 2.0;
  A.triangularView<Eigen::Lower>().transpose().solveInPlace(alpha);
  value += -0.5 * quad - 0.5 * logdet - 0.5 * n * kLog2Pi;

  if (grad) {
    // dLML/dp = 0.5 tr(W dK/dp), W = alpha alpha^T - K^-1, summed over the lower triangle once
    trtri_lower(A);
    lauum_lower(A);
    double gs = 0.0, gn = 0.0;
    for (int b = 0; b < n; ++b) {
      const double* kinv = A.col(b).data();
      const double* kb = K.col(b).data();
      double* gb = G.col(b).data();
      const double ab = alpha[b];
      const double wbb = ab * ab - kinv[b];
      gs += 0.5 * wbb * s;
      gn += 0.5 * wbb;
      for (int a = b + 1; a < n; ++a) {
        const double w = alpha[a] * ab - kinv[a];
        gs += w * kb[a];    // s dK/ds = K (off the diagonal)
        gb[a] = w * gb[a];  // l_i dk/dl_i = gneg ((a_i - b_i) / l_i)^2
      }
    }
    // gl_i = sum over the pairs of (w gneg) ((a_i - b_i) / l_i)^2, in the pairs' order above
    Eigen::VectorXd gl = Eigen::VectorXd::Zero(d);
    const Eigen::MatrixXd Xs = Xt.transpose();  // (d x n)
    gp_pairs::ard_gradient(Xs.data(), n, d, G.data(), gl.data(), gp_pairs::default_path());
    g.head(d) += gl;
    g[d] += gs;
    g[d + 1] += (noise - cfg_.noise_floor) * gn;
    g[d + 2] = cfg_.constant_mean ? alpha.sum() : 0.0;
    *grad = g / static_cast<double>(n);
  }
  return value / n;
}

std::vector<double> GpFitResult::payload(int dim) const {
  std::vector<double> p(payload_size(dim), 0.0);
  p[0] = static_cast<double>(likelihood_evaluations);
  p[1] = theta.size() > 0 ? 1.0 : 0.0;
  for (Eigen::Index i = 0; i < theta.size(); ++i) p[2 + static_cast<std::size_t>(i)] = theta[i];
  return p;
}

GpFitResult GpFitResult::from_payload(const std::vector<double>& payload, int dim) {
  if (payload.size() != payload_size(dim))
    throw std::invalid_argument("gp: a fit result of " + std::to_string(payload.size()) + " values, expected " +
                                std::to_string(payload_size(dim)));
  GpFitResult r;
  r.likelihood_evaluations = static_cast<std::int64_t>(payload[0]);
  if (payload[1] != 0.0) r.theta = Eigen::Map<const Eigen::VectorXd>(payload.data() + 2, dim + 3);
  return r;
}

GpFitStarts GaussianProcess::begin_fit(Rng& rng) {
  GpFitStarts starts;
  if (n_ == 0) return starts;  // nothing to fit; rng untouched
  standardize();               // points added since the last refit join the standardization
  const int d = dim_;
  const int p = d + (cfg_.constant_mean ? 3 : 2);  // optimized coordinates (no mean for a zero mean)
  std::vector<double> lb, ub;
  fit_box(lb, ub);
  for (int attempt = 0; attempt < cfg_.fit_attempts; ++attempt) {
    GpHyperparameters start = hyper_;
    if (attempt > 0) {  // draw from the priors; rng order: lengthscales, outputscale, noise
      for (int i = 0; i < d; ++i)
        start.lengthscales[i] = sample_gamma(rng, cfg_.lengthscale_prior_concentration, cfg_.lengthscale_prior_rate);
      start.outputscale = sample_gamma(rng, cfg_.outputscale_prior_concentration, cfg_.outputscale_prior_rate);
      start.noise =
          std::max(sample_gamma(rng, cfg_.noise_prior_concentration, cfg_.noise_prior_rate), cfg_.noise_floor);
    }
    const Eigen::VectorXd t0 = theta_of(start);
    std::vector<double> x(p);
    for (int i = 0; i < p; ++i) x[i] = std::clamp(std::isnan(t0[i]) ? 0.0 : t0[i], lb[i], ub[i]);
    starts.x.push_back(std::move(x));
    starts.seeds.push_back(rng.next_u64());  // the start's nlopt::srand seed
  }
  return starts;
}

GpFitResult GaussianProcess::search_fit(const GpFitStarts& starts) {
  GpFitResult result;
  const int d = dim_;
  std::vector<double> lb, ub;
  fit_box(lb, ub);
  const std::int64_t evaluations_before = likelihood_evaluations_;
  FitProblem problem{this, d + 3};
  double best_value = -std::numeric_limits<double>::infinity();
  for (std::size_t attempt = 0; attempt < starts.x.size(); ++attempt) {
    std::vector<double> x = starts.x[attempt];
    const int p = static_cast<int>(x.size());
    nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(p));
    opt.set_lower_bounds(lb);
    opt.set_upper_bounds(ub);
    opt.set_min_objective(neg_objective, &problem);
    opt.set_maxeval(cfg_.fit_max_evaluations);
    opt.set_ftol_rel(1e-9);
    opt.set_xtol_rel(1e-9);
    nlopt::srand(starts.seeds[attempt]);
    double f = 0.0;
    try {
      opt.optimize(x, f);
    } catch (const std::runtime_error&) {
      // roundoff_limited, forced_stop or a generic failure: x already holds the best point found
    }
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(d + 3);
    for (int i = 0; i < p; ++i) theta[i] = x[i];
    const double v = fit_objective(theta, nullptr);
    if (std::isfinite(v) && v > kFailedObjective && v > best_value) {
      best_value = v;
      result.theta = theta;
    }
  }
  result.likelihood_evaluations = likelihood_evaluations_ - evaluations_before;
  return result;
}

void GaussianProcess::end_fit(const GpFitStarts& starts, const GpFitResult& result, bool recalled) {
  if (starts.x.empty()) return;  // there was nothing to fit
  if (recalled) {
    // what search_fit leaves behind: NLopt seeded by each start in turn, the evaluations counted
    for (const std::uint64_t seed : starts.seeds) nlopt::srand(seed);
    const double n3 = static_cast<double>(n_) * n_ * n_;
    for (std::int64_t k = 0; k < result.likelihood_evaluations; ++k) likelihood_n3_ += n3;
    likelihood_evaluations_ += result.likelihood_evaluations;
  }
  if (result.theta.size() > 0) {
    if (result.theta.size() != dim_ + 3) throw std::invalid_argument("gp: a fit result of the wrong dimension");
    hyper_ = hyper_of(result.theta);
  } else {
    ++fit_failures_;
  }
  rescale_inputs();
  refactor();
}

void GaussianProcess::fit(Rng& rng) {
  const GpFitStarts starts = begin_fit(rng);
  if (starts.x.empty()) return;
  end_fit(starts, search_fit(starts), /*recalled=*/false);
}

void GaussianProcess::fit_box(std::vector<double>& lb, std::vector<double>& ub) const {
  const int d = dim_;
  const int p = d + (cfg_.constant_mean ? 3 : 2);
  lb.assign(p, 0.0);
  ub.assign(p, 0.0);
  for (int i = 0; i < d; ++i) {
    lb[i] = kLogLengthscaleMin;
    ub[i] = kLogLengthscaleMax;
  }
  lb[d] = kLogOutputscaleMin;
  ub[d] = kLogOutputscaleMax;
  lb[d + 1] = kLogNoiseExcessMin;
  ub[d + 1] = kLogNoiseExcessMax;
  if (cfg_.constant_mean) {
    lb[d + 2] = -kMeanBound;
    ub[d + 2] = kMeanBound;
  }
}

std::uint64_t GaussianProcess::digest() const {
  const auto doubles = [](const Eigen::VectorXd& v) {
    return std::span<const double>(v.data(), static_cast<std::size_t>(v.size()));
  };
  std::uint64_t h = work_key(kWorkKeyStart, inputs_digest_);
  h = work_key(h, static_cast<std::uint64_t>(n_));
  h = work_key(h, doubles(y_raw_));
  h = work_key(h, doubles(y_std_));
  h = work_key(h, doubles(hyper_.lengthscales));
  const double scalars[] = {hyper_.outputscale, hyper_.noise, hyper_.mean, y_mean_, y_scale_, jitter_};
  return work_key(h, scalars);
}

std::uint64_t GaussianProcess::fit_key(const GpFitStarts& starts) const {
  std::uint64_t h = fnv1a64("gp fit", digest());
  for (const auto& x : starts.x) h = work_key(h, x);
  for (const std::uint64_t seed : starts.seeds) h = work_key(h, seed);
  return h;
}

// ---------------------------------------------------------------------------------------------
// prediction

void GaussianProcess::predict(const Eigen::VectorXd& x, double* mean, double* variance, Eigen::VectorXd* dmean,
                              Eigen::VectorXd* dvariance) const {
  const int n = n_, d = dim_;
  if (x.size() != d)
    throw std::invalid_argument("gp: predict at " + std::to_string(x.size()) + " coordinates for dimension " +
                                std::to_string(d));
  const double s = hyper_.outputscale, scale2 = y_scale_ * y_scale_;
  const bool grads = dmean != nullptr || dvariance != nullptr;
  if (dmean) dmean->setZero(d);
  if (dvariance) dvariance->setZero(d);
  if (n == 0) {  // prior
    if (mean) *mean = y_mean_ + y_scale_ * hyper_.mean;
    if (variance) *variance = scale2 * std::max(s, cfg_.min_variance);
    return;
  }

  thread_local std::vector<double> buf_xs, buf_k, buf_g, buf_w;
  Eigen::Map<Eigen::VectorXd> xs(scratch(buf_xs, d), d);
  Eigen::Map<Eigen::VectorXd> k(scratch(buf_k, n), n);                          // k(X, x), then v = L^-1 k
  Eigen::Map<Eigen::VectorXd> g(scratch(buf_g, grads ? n : 0), grads ? n : 0);  // -(dk/dr) / r
  xs = x.cwiseQuotient(hyper_.lengthscales);
  if (grads) {
    for (int i = 0; i < n; ++i) k[i] = matern_r2(s, sqdist(Xs_.col(i).data(), xs.data(), d), &g[i]);
  } else {
    for (int i = 0; i < n; ++i) k[i] = matern_r2(s, sqdist(Xs_.col(i).data(), xs.data(), d), nullptr);
  }
  if (mean) *mean = y_mean_ + y_scale_ * (hyper_.mean + k.dot(alpha_));

  const bool need_var = variance != nullptr || dvariance != nullptr;
  double var_std = 0.0;
  const auto L = Lbuf_.topLeftCorner(n, n);
  if (need_var) {
    L.triangularView<Eigen::Lower>().solveInPlace(k);
    var_std = s - k.squaredNorm();
    if (variance) *variance = scale2 * std::max(var_std, cfg_.min_variance);
  }

  // dk_i/dx_j = -g_i (xs_j - Xs_ji) / l_j, so sum_i c_i dk_i/dx_j = -(xs_j sum c - (Xs c)_j) / l_j
  const auto contract = [&](Eigen::Map<Eigen::VectorXd>& c, double factor, Eigen::VectorXd& out) {
    out.noalias() = Xs_ * c;
    const double csum = c.sum();
    for (int j = 0; j < d; ++j) out[j] = factor * (out[j] - xs[j] * csum) / hyper_.lengthscales[j];
  };
  if (dvariance && var_std >= cfg_.min_variance) {
    // d var = -2 scale^2 (L^-T v)^T dk/dx
    Eigen::Map<Eigen::VectorXd> w(scratch(buf_w, n), n);
    w = k;
    L.triangularView<Eigen::Lower>().transpose().solveInPlace(w);
    w.array() *= g.array();
    contract(w, -2.0 * scale2, *dvariance);
  }
  if (dmean) {
    k = alpha_.cwiseProduct(g);  // v no longer needed
    contract(k, y_scale_, *dmean);
  }
}

}  // namespace dsb
