#include "optimizers/bo/acquisition.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlopt.hpp>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"
#include "optimizers/bo/sobol.hpp"
#include "optimizers/core/work_memo.hpp"

namespace dsb {

void LcbConfig::validate(const std::string& owner) const {
  const FieldCheck check(owner);
  check.require(beta >= 0.0 && std::isfinite(beta), "beta", "must be finite and >= 0");
  check.require(raw_samples >= 1, "raw_samples", "must be >= 1");
  check.require(restarts >= 1 && restarts <= raw_samples, "restarts", "must be in 1..raw_samples");
  check.require(max_evaluations >= 1, "max_evaluations", "must be >= 1");
}

nlohmann::json LcbConfig::to_json() const { return fields_json(*this); }

double lcb(const GaussianProcess& gp, double beta, const Eigen::VectorXd& u, Eigen::VectorXd* grad) {
  double mean = 0.0, var = 0.0;
  Eigen::VectorXd dmean, dvar;
  gp.predict(u, &mean, &var, grad ? &dmean : nullptr, grad ? &dvar : nullptr);
  const double sd = std::sqrt(var);
  const double a = std::sqrt(beta);
  // LCB = mu - sqrt(beta) sigma;  d sigma = d var / (2 sigma)
  if (grad) *grad = dmean - (a / (2.0 * sd)) * dvar;
  return mean - a * sd;
}

namespace {

struct LcbProblem {
  const GaussianProcess* gp;
  double beta;
};

double lcb_for_nlopt(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  const auto* p = static_cast<const LcbProblem*>(data);
  const Eigen::Map<const Eigen::VectorXd> u(x.data(), static_cast<Eigen::Index>(x.size()));
  if (grad.empty()) return lcb(*p->gp, p->beta, u, nullptr);
  Eigen::VectorXd g;
  const double v = lcb(*p->gp, p->beta, u, &g);
  for (std::size_t i = 0; i < grad.size(); ++i) grad[i] = g[static_cast<Eigen::Index>(i)];
  return v;
}

}  // namespace

Eigen::VectorXd minimize_lcb(const GaussianProcess& gp, const LcbConfig& cfg, Rng& rng) {
  SobolSequence sobol(gp.dim(), &rng);
  return minimize_lcb(gp, cfg, sobol);
}

std::uint64_t lcb_argmin_key(const GaussianProcess& gp, const LcbConfig& cfg, const SobolSequence& raw) {
  std::uint64_t h = fnv1a64("lcb argmin", gp.digest());
  const double settings[] = {cfg.beta, static_cast<double>(cfg.raw_samples), static_cast<double>(cfg.restarts),
                             static_cast<double>(cfg.max_evaluations)};
  h = work_key(h, settings);
  for (const std::uint32_t s : raw.shift()) h = work_key(h, std::uint64_t{s});
  return h;
}

Eigen::VectorXd minimize_lcb(const GaussianProcess& gp, const LcbConfig& cfg, SobolSequence& sobol) {
  const int d = gp.dim();
  if (sobol.dim() != d)
    throw std::invalid_argument("lcb: raw samples of " + std::to_string(sobol.dim()) + " dimensions for a GP of " +
                                std::to_string(d));
  // score scrambled Sobol raw samples
  const Eigen::MatrixXd raw = sobol.draw(cfg.raw_samples);  // (raw_samples x d)
  std::vector<double> score(cfg.raw_samples);
  for (int i = 0; i < cfg.raw_samples; ++i) score[i] = lcb(gp, cfg.beta, raw.row(i).transpose(), nullptr);
  std::vector<int> order(cfg.raw_samples);
  std::iota(order.begin(), order.end(), 0);
  // the best `restarts` raw samples start local refinements (ties broken by index: deterministic)
  std::partial_sort(order.begin(), order.begin() + cfg.restarts, order.end(),
                    [&](int a, int b) { return score[a] < score[b] || (score[a] == score[b] && a < b); });

  Eigen::VectorXd best = raw.row(order[0]).transpose();
  double best_value = score[order[0]];
  LcbProblem problem{&gp, cfg.beta};
  for (int r = 0; r < cfg.restarts; ++r) {
    nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(d));
    opt.set_lower_bounds(0.0);
    opt.set_upper_bounds(1.0);
    opt.set_min_objective(lcb_for_nlopt, &problem);
    opt.set_maxeval(cfg.max_evaluations);
    opt.set_ftol_rel(1e-9);
    opt.set_xtol_rel(1e-7);
    std::vector<double> x(d);
    for (int i = 0; i < d; ++i) x[i] = raw(order[r], i);
    double value = score[order[r]];
    try {
      opt.optimize(x, value);
    } catch (const nlopt::roundoff_limited&) {
      // x holds the best point found: keep it
    } catch (const std::runtime_error&) {
      continue;  // a failed refinement keeps the raw sample
    }
    // NLopt keeps x in the bounds; re-evaluate to compare exactly the same quantity
    Eigen::VectorXd u = Eigen::Map<Eigen::VectorXd>(x.data(), d).cwiseMax(0.0).cwiseMin(1.0);
    const double v = lcb(gp, cfg.beta, u, nullptr);
    if (std::isfinite(v) && v < best_value) {
      best_value = v;
      best = u;
    }
  }
  return best;
}

}  // namespace dsb
