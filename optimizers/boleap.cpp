#include "optimizers/boleap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "common/error.hpp"
#include "optimizers/bo/sobol.hpp"
#include "optimizers/cmaes.hpp"

namespace dsb {

void BoLeapConfig::validate() const {
  if (population < 2) throw ConfigError("boleap", "population", "must be >= 2");
  if (!(sigma0 > 0.0 && std::isfinite(sigma0))) throw ConfigError("boleap", "sigma0", "must be finite and > 0");
  if (max_descent_steps < 1) throw ConfigError("boleap", "max_descent_steps", "must be >= 1");
  if (patience < 1) throw ConfigError("boleap", "patience", "must be >= 1");
  if (episodes_per_leap < 1) throw ConfigError("boleap", "episodes_per_leap", "must be >= 1");
  adam.validate("boleap");
  bo.validate();
}

nlohmann::json BoLeapConfig::to_json() const {
  return {{"population", population},
          {"sigma0", sigma0},
          {"max_descent_steps", max_descent_steps},
          {"patience", patience},
          {"episodes_per_leap", episodes_per_leap},
          {"elite", "best half of the population"},
          {"adam", adam.to_json()},
          {"bo", bo.to_json()}};
}

BoLeap::BoLeap(const BoLeapConfig& cfg) : cfg_(cfg) { cfg_.validate(); }

void BoLeap::minimize(Objective& f, Rng& rng) {
  if (!f.has_gradient())
    throw std::invalid_argument("boleap needs gradients, and this env is not differentiable");
  stats_ = {};
  const int d = f.dim();
  BoSurrogate model(d, cfg_.bo);
  std::vector<double> grad(d);

  // every simulated point goes to the GP (fitted only when BO proposes)
  auto simulate = [&](const Eigen::VectorXd& x) {
    ++stats_.episodes_seen;
    const double loss = f.value(std::span<const double>(x.data(), d));
    model.add(x, loss, rng, /*defer_fit=*/true);
    return loss;
  };
  auto simulate_with_grad = [&](const Eigen::VectorXd& x) {
    ++stats_.episodes_seen;
    const double loss = f.value_and_grad(std::span<const double>(x.data(), d), grad);
    model.add(x, loss, rng, /*defer_fit=*/true);
    return loss;
  };

  // initial space-filling design, as `bo`
  SobolSequence sobol(d, &rng);
  for (int i = 0; i < cfg_.bo.initial_points_for(d); ++i)
    simulate((2.0 * sobol.next().array() - 1.0).matrix());

  const int K = cfg_.population;
  for (;;) {
    // global level: BO picks the start of the next leap
    model.refit(rng);
    stats_.gp_points = model.size();
    const Eigen::VectorXd start = model.propose(rng);
    ++stats_.leaps;
    stats_.leap_episodes.push_back(0);
    int& spent = stats_.leap_episodes.back();

    CmaesConfig cma_cfg;
    cma_cfg.sigma0 = cfg_.sigma0;
    CmaState cma(start, cfg_.sigma0, K, cma_cfg);
    // a local step needs room for K samples and at least one descent step within the leap's cap
    while (spent + K < cfg_.episodes_per_leap) {
      // 1. K candidates from N(mu, sigma^2 C), simulated
      std::vector<Eigen::VectorXd> xs(K);
      std::vector<double> fs(K), flat(static_cast<std::size_t>(K) * d);
      for (int k = 0; k < K; ++k) {
        xs[k] = cma.ask(rng);
        std::copy(xs[k].begin(), xs[k].end(), flat.begin() + std::size_t(k) * d);
      }
      // one batch (evaluation and deferred GP insertion draw nothing from rng: same records); when
      // the budget ends inside it, the points that fit still reach the GP, as one at a time
      const std::int64_t used_before = f.used();
      try {
        f.values(flat, fs);
      } catch (const BudgetExhausted&) {
        for (int k = 0; k < static_cast<int>(f.used() - used_before); ++k) {
          ++stats_.episodes_seen;
          model.add(xs[k], fs[k], rng, /*defer_fit=*/true);
        }
        ++stats_.episodes_seen;  // the refused request, counted as simulate() counts it
        throw;
      }
      for (int k = 0; k < K; ++k) {
        ++stats_.episodes_seen;
        model.add(xs[k], fs[k], rng, /*defer_fit=*/true);
        ++spent;
      }
      // 2. the mean of the best half starts the descent
      std::vector<int> order(K);
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return fs[a] < fs[b]; });
      Eigen::VectorXd s = Eigen::VectorXd::Zero(d);
      const int elite = K / 2;
      for (int i = 0; i < elite; ++i) s += xs[order[i]];
      s /= elite;
      // Adam steps, each one episode with a gradient; stop after `patience` non-improving steps
      Adam adam(cfg_.adam, d);
      double best = std::numeric_limits<double>::infinity();
      int stale = 0;
      stats_.descent_lengths.push_back(0);
      stats_.stale_stops.push_back(0);
      int& steps = stats_.descent_lengths.back();
      while (steps < cfg_.max_descent_steps && spent < cfg_.episodes_per_leap) {
        const double loss = simulate_with_grad(s);
        ++spent;
        ++steps;
        if (loss < best) {
          best = loss;
          stale = 0;
        } else if (++stale >= cfg_.patience) {
          stats_.stale_stops.back() = 1;
          break;
        }
        if (!std::isfinite(loss)) break;  // failed episode: the descent ends here
        std::span<double> sx(s.data(), d);
        adam.step(sx, grad);
      }
      // 3. mu <- end of the descent; sigma and C by the CMA-ES update driven by that step
      cma.tell(xs, fs, &s);
      if (cma.should_stop()) break;  // the search distribution collapsed: back to BO early
    }
  }
}

std::unique_ptr<Optimizer> make_boleap(const BoLeapConfig& cfg) {
  return std::make_unique<BoLeap>(cfg);
}

}  // namespace dsb
