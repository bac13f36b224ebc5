// CMA-ES (cmaes-library rules) with IPOP restarts. See cmaes.hpp for what follows the library and
// where it deviates. "eq. N" = N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv 1604.00772.
#include "optimizers/cmaes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <stdexcept>

#include "common/config_fields.hpp"
#include "common/det_math.hpp"
#include "common/field_check.hpp"
#include "common/number_text.hpp"
#include "common/unit_box.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {

namespace {

constexpr double kEps = 1e-8;            // library _EPS: eigenvalue floor, negative-weight denominator
constexpr double kSigmaMax = 1e32;       // library _SIGMA_MAX
constexpr int kMaxPopulation = 1 << 28;  // IPOP growth stops here (int overflow guard only)

}  // namespace

// ---------------------------------------------------------------------------------------------
// config

void CmaesConfig::validate() const {
  const FieldCheck check("cmaes");
  check.number_above("sigma0", sigma0, 0.0);
  check.require(population == 0 || population >= 2, "population",
                "must be 0 (default 4 + floor(3 ln n)) or >= 2 (got " + std::to_string(population) + ")");
  check.require(max_resampling >= 0, "max_resampling", "must be >= 0 (got " + std::to_string(max_resampling) + ")");
  check.number_at_least("ipop_factor", ipop_factor, 1.0);
  check.number_at_least("tolfun", tolfun, 0.0);
  check.number_at_least("tolx_factor", tolx_factor, 0.0);
  check.require(tolxup > 0.0, "tolxup", "must be > 0 (got " + number_text(tolxup) + ")");
  check.require(condition_max > 1.0, "condition_max", "must be > 1 (got " + number_text(condition_max) + ")");
}

nlohmann::json CmaesConfig::to_json() const { return fields_json(*this); }

const char* to_string(CmaStop s) {
  switch (s) {
    case CmaStop::none: return "none";
    case CmaStop::numerical: return "numerical";
    case CmaStop::tolfun: return "tolfun";
    case CmaStop::tolx: return "tolx";
    case CmaStop::tolxup: return "tolxup";
    case CmaStop::noeffectcoord: return "noeffectcoord";
    case CmaStop::noeffectaxis: return "noeffectaxis";
    case CmaStop::conditioncov: return "conditioncov";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
// constants

// lambda = 4 + floor(3 ln n)   (eq. 48)
int cmaes_default_population(int n) {
  if (n < 1) throw std::invalid_argument("cmaes: dimension must be >= 1");
  return 4 + static_cast<int>(std::floor(3.0 * dm::log(static_cast<double>(n))));
}

CmaesConstants cmaes_constants(int n, int lambda) {
  if (n < 1) throw std::invalid_argument("cmaes: dimension must be >= 1");
  if (lambda < 2) throw std::invalid_argument("cmaes: population must be >= 2");
  const double nd = n;
  CmaesConstants k;
  k.lambda = lambda;
  k.mu = lambda / 2;

  // w'_i = ln((lambda + 1) / 2) - ln i, i = 1..lambda, for all lambda (eq. 49, active CMA)
  std::vector<double> wp(lambda);
  for (int i = 0; i < lambda; ++i) wp[i] = dm::log((lambda + 1) / 2.0) - dm::log(i + 1.0);

  // mu_eff over the first mu weights, mu_eff^- over the last lambda - mu   (eq. 49 text, 51)
  auto eff = [&](int lo, int hi) {
    double s = 0.0, s2 = 0.0;
    for (int i = lo; i < hi; ++i) {
      s += wp[i];
      s2 += wp[i] * wp[i];
    }
    return s * s / s2;
  };
  k.mu_eff = eff(0, k.mu);
  k.mu_eff_minus = eff(k.mu, lambda);

  // c1 = alpha_cov / ((n + 1.3)^2 + mu_eff), alpha_cov = 2   (eq. 57)
  const double alpha_cov = 2.0;
  k.c1 = alpha_cov / ((nd + 1.3) * (nd + 1.3) + k.mu_eff);
  // cmu = min(1 - c1 - 1e-8, alpha_cov (mu_eff - 2 + 1/mu_eff) / ((n+2)^2 + alpha_cov mu_eff / 2))
  // (eq. 58; the -1e-8 is the library's large-lambda fix, PR #49)
  k.cmu =
      std::min(1.0 - k.c1 - 1e-8,
               alpha_cov * (k.mu_eff - 2.0 + 1.0 / k.mu_eff) / ((nd + 2.0) * (nd + 2.0) + alpha_cov * k.mu_eff / 2.0));

  // alpha_min = min(alpha_mu^-, alpha_mueff^-, alpha_posdef^-)   (eq. 50-52)
  const double alpha_mu = 1.0 + k.c1 / k.cmu;
  const double alpha_mueff = 1.0 + 2.0 * k.mu_eff_minus / (k.mu_eff + 2.0);
  const double alpha_posdef = (1.0 - k.c1 - k.cmu) / (nd * k.cmu);
  k.alpha_min = std::min({alpha_mu, alpha_mueff, alpha_posdef});

  // w_i = w'_i / sum|w'+| for w'_i >= 0, alpha_min w'_i / sum|w'-| otherwise   (eq. 53)
  double pos = 0.0, neg = 0.0;
  for (double w : wp) (w >= 0.0 ? pos : neg) += std::abs(w);
  k.weights.resize(lambda);
  for (int i = 0; i < lambda; ++i) k.weights[i] = wp[i] >= 0.0 ? wp[i] / pos : k.alpha_min * wp[i] / neg;

  // c_sigma = (mu_eff + 2) / (n + mu_eff + 5); d_sigma = 1 + 2 max(0, sqrt((mu_eff-1)/(n+1)) - 1) + c_sigma   (eq. 55)
  k.c_sigma = (k.mu_eff + 2.0) / (nd + k.mu_eff + 5.0);
  k.d_sigma = 1.0 + 2.0 * std::max(0.0, std::sqrt((k.mu_eff - 1.0) / (nd + 1.0)) - 1.0) + k.c_sigma;
  // c_c = (4 + mu_eff / n) / (n + 4 + 2 mu_eff / n)   (eq. 56)
  k.c_c = (4.0 + k.mu_eff / nd) / (nd + 4.0 + 2.0 * k.mu_eff / nd);
  // E||N(0, I)|| ~ sqrt(n) (1 - 1/(4n) + 1/(21 n^2))   (text after eq. 44)
  k.chi_n = std::sqrt(nd) * (1.0 - 1.0 / (4.0 * nd) + 1.0 / (21.0 * nd * nd));
  // history length of the TolFun criterion (library): 10 + ceil(30 n / lambda)   (Appendix B.3)
  k.funhist_term = 10 + static_cast<int>(std::ceil(30.0 * nd / lambda));
  return k;
}

// ---------------------------------------------------------------------------------------------
// one CMA-ES instance

CmaState::CmaState(const Eigen::VectorXd& mean, double sigma, int lambda, const CmaesConfig& cfg)
    : n_(static_cast<int>(mean.size())),
      k_(cmaes_constants(static_cast<int>(mean.size()), lambda)),
      tolfun_(cfg.tolfun),
      tolx_(cfg.tolx_factor * sigma),
      tolxup_(cfg.tolxup),
      condition_max_(cfg.condition_max),
      max_resampling_(cfg.max_resampling),
      mean_(mean),  // a copy: no aliasing of the caller's array (library bug before v0.9.0)
      sigma_(sigma),
      C_(Eigen::MatrixXd::Identity(n_, n_)),
      p_sigma_(Eigen::VectorXd::Zero(n_)),
      p_c_(Eigen::VectorXd::Zero(n_)),
      funhist_(2 * static_cast<std::size_t>(k_.funhist_term), 0.0) {
  if (!(sigma > 0.0) || !std::isfinite(sigma)) throw std::invalid_argument("cmaes: sigma must be > 0");
}

// C <- (C + C^T)/2; C = B diag(D^2) B^T with negative eigenvalues -> 1e-8; C rebuilt from B, D
// (tutorial Sec. 2 and B.2; the library's _eigen_decomposition)
bool CmaState::eigen_decomposition() {
  if (have_eigen_) return !eigen_failed_;
  const Eigen::MatrixXd sym = 0.5 * (C_ + C_.transpose());
  C_ = sym;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(C_, Eigen::ComputeEigenvectors);
  have_eigen_ = true;
  if (es.info() != Eigen::Success || !es.eigenvalues().allFinite() || !es.eigenvectors().allFinite()) {
    eigen_failed_ = true;
    return false;
  }
  eigen_failed_ = false;
  B_ = es.eigenvectors();
  Eigen::VectorXd d2 = es.eigenvalues();  // ascending, as numpy.linalg.eigh
  for (int i = 0; i < n_; ++i)
    if (d2[i] < 0.0) d2[i] = kEps;
  D_ = d2.cwiseSqrt();
  C_ = B_ * D_.cwiseProduct(D_).asDiagonal() * B_.transpose();
  return true;
}

// z ~ N(0, I) (eq. 38); y = B D z ~ N(0, C) (eq. 39); x = m + sigma y (eq. 40)
Eigen::VectorXd CmaState::sample(Rng& rng) const {
  Eigen::VectorXd z(n_);
  for (int i = 0; i < n_; ++i) z[i] = rng.normal();
  const Eigen::VectorXd y = B_ * D_.cwiseProduct(z);
  return mean_ + sigma_ * y;
}

Eigen::VectorXd CmaState::ask(Rng& rng) {
  if (!eigen_decomposition()) throw std::runtime_error("cmaes: eigendecomposition of C failed");
  auto inside = [](const Eigen::VectorXd& x) { return inside_box({x.data(), static_cast<std::size_t>(x.size())}); };
  // bounds (library): resample up to max_resampling times, then clip one more draw to the box
  for (int r = 0; r < max_resampling_; ++r) {
    Eigen::VectorXd x = sample(rng);
    if (inside(x)) return x;
  }
  Eigen::VectorXd x = sample(rng);
  for (int i = 0; i < n_; ++i) x[i] = std::clamp(x[i], -1.0, 1.0);
  return x;
}

void CmaState::tell(const std::vector<Eigen::VectorXd>& xs, const std::vector<double>& fs,
                    const Eigen::VectorXd* moved_mean) {
  const int lambda = k_.lambda, mu = k_.mu;
  if (static_cast<int>(xs.size()) != lambda || static_cast<int>(fs.size()) != lambda)
    throw std::invalid_argument("cmaes: tell needs exactly lambda = " + std::to_string(lambda) + " solutions");
  for (const auto& x : xs)
    if (x.size() != n_) throw std::invalid_argument("cmaes: told solution has the wrong dimension");

  // 1. g += 1; sort by f ascending (stable, as Python's sort; NaN counts as +inf)
  ++g_;
  std::vector<double> f(fs);
  for (double& v : f)
    if (std::isnan(v)) v = std::numeric_limits<double>::infinity();
  std::vector<int> order(lambda);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return f[a] < f[b]; });

  // 2. best and worst f into the ring buffer (slot g mod funhist_term)   (TolFun history, B.3)
  const std::size_t slot = 2 * static_cast<std::size_t>(g_ % k_.funhist_term);
  funhist_[slot] = f[order.front()];
  funhist_[slot + 1] = f[order.back()];

  // 3. B, D of the pre-update C (cached since ask), then invalidate the cache
  if (!eigen_decomposition()) throw std::runtime_error("cmaes: eigendecomposition of C failed");
  const Eigen::MatrixXd B = B_;
  const Eigen::VectorXd D = D_;
  have_eigen_ = false;

  // 4. y_k = (x_k - m) / sigma (sorted); <y>_w = sum_{i<=mu} w_i y_i:lambda (eq. 41); m += c_m sigma <y>_w (eq. 42)
  Eigen::MatrixXd Y(n_, lambda);
  for (int i = 0; i < lambda; ++i) Y.col(i) = (xs[order[i]] - mean_) / sigma_;
  Eigen::VectorXd y_w = Eigen::VectorXd::Zero(n_);
  for (int i = 0; i < mu; ++i) y_w += k_.weights[i] * Y.col(i);
  const double c_m = 1.0;
  if (moved_mean) {
    // BO-Leap: the step is where the gradient descent ended, not the sample's weighted mean
    if (moved_mean->size() != n_) throw std::invalid_argument("cmaes: moved mean has the wrong dimension");
    y_w = (*moved_mean - mean_) / sigma_;
    mean_ = *moved_mean;
  } else {
    mean_ += c_m * sigma_ * y_w;
  }

  // 5. C^-1/2 = B D^-1 B^T (Sec. 2); p_sigma <- (1 - c_s) p_sigma + sqrt(c_s (2 - c_s) mu_eff) C^-1/2 <y>_w   (eq. 43)
  const Eigen::MatrixXd C_inv_sqrt = B * D.cwiseInverse().asDiagonal() * B.transpose();
  const double cs = k_.c_sigma;
  p_sigma_ = (1.0 - cs) * p_sigma_ + std::sqrt(cs * (2.0 - cs) * k_.mu_eff) * (C_inv_sqrt * y_w);
  const double norm_p_sigma = p_sigma_.norm();

  // 6. sigma <- sigma exp((c_s / d_s)(||p_sigma|| / E||N(0,I)|| - 1))   (eq. 44), capped at 1e32 (library)
  sigma_ *= dm::exp((cs / k_.d_sigma) * (norm_p_sigma / k_.chi_n - 1.0));
  sigma_ = std::min(sigma_, kSigmaMax);

  // 7. h_sigma (text after eq. 47), with the library's exponent 2 (g + 1) on the incremented g
  const double h_left = norm_p_sigma / std::sqrt(1.0 - dm::pow(1.0 - cs, 2.0 * (g_ + 1)));
  const double h_right = (1.4 + 2.0 / (n_ + 1.0)) * k_.chi_n;
  const double h_sigma = h_left < h_right ? 1.0 : 0.0;

  // 8. p_c <- (1 - c_c) p_c + h_sigma sqrt(c_c (2 - c_c) mu_eff) <y>_w   (eq. 45)
  const double cc = k_.c_c;
  p_c_ = (1.0 - cc) * p_c_ + h_sigma * std::sqrt(cc * (2.0 - cc) * k_.mu_eff) * y_w;

  // 9. w°_i = w_i if w_i >= 0, else w_i n / (||C^-1/2 y_i||^2 + 1e-8)   (eq. 46, library's epsilon)
  Eigen::VectorXd w_io(lambda);
  for (int i = 0; i < lambda; ++i) {
    const double w = k_.weights[i];
    w_io[i] = w >= 0.0 ? w : w * (n_ / ((C_inv_sqrt * Y.col(i)).squaredNorm() + kEps));
  }

  // 10. C <- (1 + c1 delta(h_sigma) - c1 - cmu sum_j w_j) C + c1 p_c p_c^T + cmu sum_i w°_i y_i y_i^T   (eq. 47)
  const double delta_h = (1.0 - h_sigma) * cc * (2.0 - cc);
  double sum_w = 0.0;
  for (double w : k_.weights) sum_w += w;
  const Eigen::MatrixXd rank_one = p_c_ * p_c_.transpose();
  const Eigen::MatrixXd rank_mu = Y * w_io.asDiagonal() * Y.transpose();
  C_ = (1.0 + k_.c1 * delta_h - k_.c1 - k_.cmu * sum_w) * C_ + k_.c1 * rank_one + k_.cmu * rank_mu;
}

bool CmaState::should_stop() {
  stop_ = CmaStop::none;
  // deviation: non-finite state (the library would raise or carry NaN) counts as a stop
  if (!std::isfinite(sigma_) || !mean_.allFinite() || !C_.allFinite() || !eigen_decomposition()) {
    stop_ = CmaStop::numerical;
    return true;
  }
  const Eigen::VectorXd dC = C_.diagonal();

  // TolFun (history): g > funhist_term and range of the recent best/worst values < tolfun
  if (g_ > k_.funhist_term) {
    const auto [lo, hi] = std::minmax_element(funhist_.begin(), funhist_.end());
    if (*hi - *lo < tolfun_) {
      stop_ = CmaStop::tolfun;
      return true;
    }
  }
  // TolX: all sigma C_ii < tolx and all sigma p_c,i < tolx (library: variance, signed p_c)
  {
    bool all = true;
    for (int i = 0; i < n_ && all; ++i) all = sigma_ * dC[i] < tolx_ && sigma_ * p_c_[i] < tolx_;
    if (all) {
      stop_ = CmaStop::tolx;
      return true;
    }
  }
  // TolXUp: sigma max(D) > tolxup (absolute threshold, library)
  if (sigma_ * D_.maxCoeff() > tolxup_) {
    stop_ = CmaStop::tolxup;
    return true;
  }
  // NoEffectCoord: any m_i == m_i + 0.2 sigma sqrt(C_ii)
  for (int i = 0; i < n_; ++i) {
    if (mean_[i] == mean_[i] + 0.2 * sigma_ * std::sqrt(dC[i])) {
      stop_ = CmaStop::noeffectcoord;
      return true;
    }
  }
  // NoEffectAxis: axis i = g mod n; all m == m + 0.1 sigma D_i B[:, i]
  {
    const int a = g_ % n_;
    bool all = true;
    for (int j = 0; j < n_ && all; ++j) all = mean_[j] == mean_[j] + 0.1 * sigma_ * D_[a] * B_(j, a);
    if (all) {
      stop_ = CmaStop::noeffectaxis;
      return true;
    }
  }
  // ConditionCov: max(D) / min(D) > condition_max, D = sqrt of C's eigenvalues (library)
  if (D_.maxCoeff() / D_.minCoeff() > condition_max_) {
    stop_ = CmaStop::conditioncov;
    return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// optimizer: generations of ask / evaluate / tell, IPOP restarts on stop

Cmaes::Cmaes(const CmaesConfig& cfg) : ConfiguredOptimizer("cmaes", false, cfg) {}

void Cmaes::minimize(Objective& f, Rng& rng) {
  cfg_.validate();
  stats_ = CmaesRunStats{};
  const int n = f.dim();
  if (n < 1) throw std::invalid_argument("cmaes: objective dimension must be >= 1");
  int lambda = cfg_.population > 0 ? cfg_.population : cmaes_default_population(n);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(n);  // box centre

  std::vector<Eigen::VectorXd> xs;
  std::vector<double> flat, fs;
  for (;;) {
    CmaState es(mean, cfg_.sigma0, lambda, cfg_);
    stats_.populations.push_back(lambda);
    stats_.instance_generations.push_back(0);
    stats_.final_sigma = es.sigma();
    for (;;) {
      xs.clear();
      for (int k = 0; k < lambda; ++k) xs.push_back(es.ask(rng));
      // the population as one batch (evaluation draws nothing from rng, so asking first changes
      // nothing); throws BudgetExhausted when the budget is spent: it ends the run, by design
      flat.resize(static_cast<std::size_t>(lambda) * n);
      for (int k = 0; k < lambda; ++k) std::copy(xs[k].begin(), xs[k].end(), flat.begin() + std::size_t(k) * n);
      fs.resize(lambda);
      f.values(flat, fs);
      for (double& v : fs)
        if (std::isnan(v)) v = std::numeric_limits<double>::infinity();  // failed episode = worst
      es.tell(xs, fs);
      ++stats_.generations;
      ++stats_.instance_generations.back();
      stats_.final_sigma = es.sigma();
      if (es.should_stop()) break;
    }
    stats_.stops.push_back(es.stop_reason());
    if (!cfg_.ipop) return;
    // IPOP (examples/ipop_cma.py): population x factor, new uniform mean in the box, same sigma0
    const double next = std::round(lambda * cfg_.ipop_factor);
    lambda = next >= kMaxPopulation ? kMaxPopulation : static_cast<int>(next);
    for (int i = 0; i < n; ++i) mean[i] = rng.uniform(-1.0, 1.0);
  }
}

nlohmann::json Cmaes::diagnostics() const {
  nlohmann::json d = {
      {"restarts", stats_.restarts()}, {"generations", stats_.generations}, {"final_sigma", stats_.final_sigma}};
  put_capped(d, "instances", stats_.populations, [&](int lambda, std::size_t i) {
    const bool stopped = i < stats_.stops.size();
    return nlohmann::json{{"population", lambda},
                          {"generations", stats_.instance_generations[i]},
                          {"stop", stopped ? to_string(stats_.stops[i]) : "budget"}};
  });
  return d;
}

std::unique_ptr<Optimizer> make_cmaes(const CmaesConfig& cfg) { return std::make_unique<Cmaes>(cfg); }

KnobTable cmaes_knobs(CmaesConfig& cfg) {
  KnobTable t("cmaes");
  t.add("sigma0", &cfg.sigma0).add("population", &cfg.population);
  t.add("ipop", &cfg.ipop).add("ipop_factor", &cfg.ipop_factor);
  return t;
}

std::unique_ptr<Optimizer> make_cmaes_with(const KnobSettings& settings) {
  return make_cmaes(with_knobs(cmaes_knobs, CmaesConfig{}, settings));
}

}  // namespace dsb
