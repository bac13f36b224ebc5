#include "optimizers/bo/bo.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"
#include "optimizers/bo/sobol.hpp"
#include "optimizers/core/configured_optimizer.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {

void BoConfig::validate() const {
  const FieldCheck check("bo");
  check.require(initial_points >= 0, "initial_points", "must be >= 0");
  check.require(refit_every_until >= 1, "refit_every_until", "must be >= 1");
  check.require(refit_growth > 0.0, "refit_growth", "must be > 0");
  lcb.validate("bo");
  gp.validate();
}

nlohmann::json BoConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["initial_design"] = "scrambled Sobol";
  return j;
}

int BoConfig::initial_points_for(int dim) const {
  return initial_points > 0 ? initial_points : std::clamp(dim + 1, 5, 20);
}

BoSurrogate::BoSurrogate(int dim, const BoConfig& cfg, WorkMemo* memo) : cfg_(cfg), gp_(dim, cfg.gp), memo_(memo) {}

void BoSurrogate::refit(Rng& rng) {
  const int n = size(), d = gp_.dim();
  if (n == 0) return;
  Eigen::MatrixXd X(n, d);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    X.row(i) = u_[i].transpose();
    y[i] = y_[i];
  }
  // failed episodes carry the worst finite loss seen so far
  const double fill = std::isfinite(worst_) ? worst_ : 0.0;
  for (int i : failed_) y[i] = fill;
  gp_.set_data(X, y);
  // the hyperparameter search, or its result recalled from the memo
  const GpFitStarts starts = gp_.begin_fit(rng);
  std::vector<double> recalled(GpFitResult::payload_size(d));
  const std::uint64_t key = memo_ ? gp_.fit_key(starts) : 0;
  if (memo_ && memo_->recall(key, recalled)) {
    gp_.end_fit(starts, GpFitResult::from_payload(recalled, d), /*recalled=*/true);
    ++fits_recalled_;
  } else {
    const GpFitResult result = gp_.search_fit(starts);
    if (memo_) memo_->remember(key, result.payload(d));
    gp_.end_fit(starts, result, /*recalled=*/false);
  }
  last_fit_n_ = n;
  factored_n_ = n;
  ++fits_;
}

void BoSurrogate::add(const Eigen::VectorXd& x, double loss, Rng& rng, bool defer_fit) {
  Eigen::VectorXd u = (x.array() + 1.0) * 0.5;  // [-1,1] -> [0,1]
  u_.push_back(u);
  if (std::isfinite(loss)) {
    worst_ = std::max(worst_, loss);
    y_.push_back(loss);
  } else {
    failed_.push_back(size());
    y_.push_back(std::isfinite(worst_) ? worst_ : 0.0);
  }
  if (defer_fit) return;
  const int n = size();
  const bool refit_now =
      n <= cfg_.refit_every_until || n >= static_cast<int>(std::ceil((1.0 + cfg_.refit_growth) * last_fit_n_));
  if (refit_now || factored_n_ != n - 1) {
    refit(rng);
  } else {
    gp_.add_point(u, y_.back());  // O(n^2) extension with the current hyperparameters
    factored_n_ = n;
  }
}

nlohmann::json BoSurrogate::diagnostics() const {
  const GpHyperparameters& h = gp_.hyperparameters();
  const std::vector<double> lengthscales(h.lengthscales.data(), h.lengthscales.data() + h.lengthscales.size());
  nlohmann::json hyper = {{"outputscale", h.outputscale}, {"noise", h.noise}, {"mean", h.mean}};
  put_capped(hyper, "lengthscales", lengthscales, [](double l, std::size_t) { return l; });
  return {{"points", size()},
          {"failed_points", failed_.size()},
          {"gp_fits", fits_},
          {"gp_fit_failures", gp_.fit_failures()},
          {"likelihood_evaluations", gp_.likelihood_evaluations()},
          {"likelihood_n3", gp_.likelihood_n3()},
          {"jitter", gp_.jitter()},
          {"hyperparameters", std::move(hyper)}};
}

Eigen::VectorXd BoSurrogate::propose(Rng& rng) {
  // the LCB argmin, or its result recalled from the memo
  SobolSequence raw(gp_.dim(), &rng);  // the raw samples' scramble: what minimize_lcb draws
  Eigen::VectorXd u(gp_.dim());
  const std::uint64_t key = memo_ ? lcb_argmin_key(gp_, cfg_.lcb, raw) : 0;
  ++proposals_;
  if (memo_ && memo_->recall(key, std::span<double>(u.data(), static_cast<std::size_t>(u.size())))) {
    ++proposals_recalled_;
  } else {
    u = minimize_lcb(gp_, cfg_.lcb, raw);
    if (memo_) memo_->remember(key, std::span<const double>(u.data(), static_cast<std::size_t>(u.size())));
  }
  return (2.0 * u.array() - 1.0).cwiseMax(-1.0).cwiseMin(1.0);
}

namespace {

class BayesOpt : public ConfiguredOptimizer<BoConfig> {
 public:
  explicit BayesOpt(const BoConfig& cfg) : ConfiguredOptimizer("bo", false, cfg) {}

  void minimize(Objective& f, Rng& rng) override {
    diagnostics_ = nlohmann::json::object();
    BoSurrogate model(f.dim(), cfg_, &f);
    try {
      search(f, rng, model);
    } catch (...) {
      // the normal end (BudgetExhausted) or a failure: keep what the model knows
      diagnostics_ = model.diagnostics();
      throw;
    }
    diagnostics_ = model.diagnostics();
  }
  nlohmann::json diagnostics() const override { return diagnostics_; }

 private:
  void search(Objective& f, Rng& rng, BoSurrogate& model) {
    const int d = f.dim();
    // space-filling initial design: scrambled Sobol in the unit box
    const int n_init = cfg_.initial_points_for(d);
    SobolSequence sobol(d, &rng);
    for (int i = 0; i < n_init; ++i) {
      const Eigen::VectorXd x = (2.0 * sobol.next().array() - 1.0).matrix();
      const double loss = f.value(std::span<const double>(x.data(), d));
      model.add(x, loss, rng, /*defer_fit=*/i + 1 < n_init);
    }
    // one LCB minimizer per episode until the budget ends
    for (;;) {
      const Eigen::VectorXd x = model.propose(rng);
      const double loss = f.value(std::span<const double>(x.data(), d));
      model.add(x, loss, rng);
    }
  }

  nlohmann::json diagnostics_ = nlohmann::json::object();
};

}  // namespace

std::unique_ptr<Optimizer> make_bo(const BoConfig& cfg) { return std::make_unique<BayesOpt>(cfg); }

}  // namespace dsb
