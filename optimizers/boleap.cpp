#include "optimizers/boleap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "common/config_fields.hpp"
#include "common/field_check.hpp"
#include "optimizers/bo/sobol.hpp"
#include "optimizers/cmaes.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {

void BoLeapConfig::validate() const {
  const FieldCheck check("boleap");
  check.require(population >= 1, "population", "must be >= 1 (1: the ablation without samples)");
  check.require(sigma0 > 0.0 && std::isfinite(sigma0), "sigma0", "must be finite and > 0");
  check.require(max_descent_steps >= 1, "max_descent_steps", "must be >= 1");
  check.require(patience >= 1, "patience", "must be >= 1");
  check.require(episodes_per_leap >= 1, "episodes_per_leap", "must be >= 1");
  check.require(leap_iterations >= 0, "leap_iterations", "must be >= 0 (0: the leap counts episodes)");
  check.require(step_size > 0.0 && std::isfinite(step_size), "step_size", "must be finite and > 0");
  check.require(elite >= 0 && elite <= population, "elite",
                "must be in [0, population] (0 = population / 2), got " + std::to_string(elite));
  adam.validate("boleap");
  bo.validate();
}

nlohmann::json BoLeapConfig::to_json() const {
  nlohmann::json j = fields_json(*this);
  j["stop_after_non_improving_steps_over"] = patience;
  return j;
}

BoLeap::BoLeap(const BoLeapConfig& cfg) : ConfiguredOptimizer("boleap", true, cfg) {}

void BoLeap::minimize(Objective& f, Rng& rng) {
  if (!f.has_gradient()) throw std::invalid_argument("boleap needs gradients, and this env is not differentiable");
  stats_ = {};
  const int d = f.dim();
  BoSurrogate model(d, cfg_.bo, &f);
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
  for (int i = 0; i < cfg_.bo.initial_points_for(d); ++i) simulate((2.0 * sobol.next().array() - 1.0).matrix());

  const int K = cfg_.population;
  // one descent from s, at most J gradient episodes within the leap's episode cap; a step is Adam's
  // or a plain clipped gradient step
  auto descend = [&](Eigen::VectorXd& s, Adam& adam, int& spent) {
    double best = std::numeric_limits<double>::infinity();
    int stale = 0;
    stats_.descent_lengths.push_back(0);
    stats_.stale_stops.push_back(0);
    stats_.descent_leap.push_back(stats_.leaps - 1);
    stats_.descent_first_loss.push_back(std::numeric_limits<double>::quiet_NaN());
    stats_.descent_best_loss.push_back(std::numeric_limits<double>::quiet_NaN());
    int& steps = stats_.descent_lengths.back();
    const bool capped = cfg_.leap_iterations == 0;
    while (steps < cfg_.max_descent_steps && (!capped || spent < cfg_.episodes_per_leap)) {
      const double loss = simulate_with_grad(s);
      ++spent;
      ++steps;
      if (steps == 1) stats_.descent_first_loss.back() = loss;
      if (loss < best) {
        best = loss;
        stats_.descent_best_loss.back() = best;
        stale = 0;
      } else if (++stale > cfg_.patience) {  // stagnated or increased for more than `patience` steps
        stats_.stale_stops.back() = 1;
        break;
      }
      if (!std::isfinite(loss)) break;  // failed episode: the descent ends here
      std::span<double> sx(s.data(), d);
      if (cfg_.plain_steps) {
        // x <- clip(x - alpha g, -1, 1): the paper's gradient step, clipped to stay in the box
        for (int i = 0; i < d; ++i) s[i] = std::clamp(s[i] - cfg_.step_size * grad[i], -1.0, 1.0);
      } else {
        adam.step(sx, grad);
      }
    }
  };

  for (;;) {
    // global level: BO picks the start of the next leap
    model.refit(rng);
    stats_.gp_points = model.size();
    stats_.gp = model.diagnostics();
    const Eigen::VectorXd start = model.propose(rng);
    ++stats_.leaps;
    stats_.leap_episodes.push_back(0);
    int& spent = stats_.leap_episodes.back();
    Adam leap_adam(cfg_.adam, d);  // one Adam state for the whole leap (adam_per_leap)

    if (K == 1) {
      // the ablation: no search distribution, one descent from BO's proposal
      Eigen::VectorXd s = start;
      descend(s, leap_adam, spent);
      stats_.leap_stops.push_back(CmaStop::none);
      continue;
    }

    CmaesConfig cma_cfg;
    cma_cfg.sigma0 = cfg_.sigma0;
    CmaState cma(start, cfg_.sigma0, K, cma_cfg);
    // a local iteration needs room for K samples and at least one descent step within the leap's
    // cap (in episodes), or the leap has its count of local iterations
    for (int iteration = 0;
         cfg_.leap_iterations > 0 ? iteration < cfg_.leap_iterations : spent + K < cfg_.episodes_per_leap;
         ++iteration) {
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
      bool exhausted = false;
      try {
        f.values(flat, fs);
      } catch (const BudgetExhausted&) {
        exhausted = true;
      }
      const int evaluated = static_cast<int>(f.used() - used_before);
      for (int k = 0; k < evaluated; ++k) {
        ++stats_.episodes_seen;
        model.add(xs[k], fs[k], rng, /*defer_fit=*/true);
        ++spent;
      }
      if (exhausted) {
        ++stats_.episodes_seen;  // the refused request, counted as simulate() counts it
        throw BudgetExhausted{};
      }
      // 2. the mean of the best half starts the descent
      std::vector<int> order(K);
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return fs[a] < fs[b]; });
      Eigen::VectorXd s = Eigen::VectorXd::Zero(d);
      const int elite = cfg_.elite_count();
      for (int i = 0; i < elite; ++i) s += xs[order[i]];
      s /= elite;
      Adam descent_adam(cfg_.adam, d);
      descend(s, cfg_.adam_per_leap ? leap_adam : descent_adam, spent);
      // 3. mu <- end of the descent; sigma and C by the CMA-ES update driven by that step
      cma.tell(xs, fs, &s);
      if (cma.should_stop()) break;  // the search distribution collapsed: back to BO early
    }
    stats_.leap_stops.push_back(cma.stop_reason());
  }
}

nlohmann::json BoLeap::diagnostics() const {
  const auto& s = stats_;
  // a descent whose first episode the budget refused never ran: not counted
  int stale = 0;
  std::vector<int> lengths;
  for (std::size_t i = 0; i < s.descent_lengths.size(); ++i) {
    if (s.descent_lengths[i] == 0) continue;
    stale += s.stale_stops[i];
    lengths.push_back(s.descent_lengths[i]);
  }
  nlohmann::json d = {{"leaps", s.leaps},
                      {"descents", lengths.size()},
                      {"stale_stops", stale},
                      {"descent_steps", summarize(lengths)},
                      {"gp", s.gp.is_null() ? nlohmann::json::object() : s.gp}};
  // per leap: its descents are the contiguous run of descent_leap == leap
  std::vector<int> leap_ids(static_cast<std::size_t>(s.leaps));
  std::iota(leap_ids.begin(), leap_ids.end(), 0);
  put_capped(d, "leap_list", leap_ids, [&](int leap, std::size_t) {
    int descents = 0, steps = 0, stale_in_leap = 0;
    double first = std::numeric_limits<double>::quiet_NaN(), end = first, best = first;
    for (std::size_t i = 0; i < s.descent_leap.size(); ++i) {
      if (s.descent_leap[i] != leap || s.descent_lengths[i] == 0) continue;
      if (descents++ == 0) first = s.descent_first_loss[i];
      steps += s.descent_lengths[i];
      stale_in_leap += s.stale_stops[i];
      end = s.descent_best_loss[i];
      if (!std::isnan(end) && (std::isnan(best) || end < best)) best = end;
    }
    const auto l = static_cast<std::size_t>(leap);
    std::string ended = "budget";
    if (l < s.leap_stops.size())
      ended = s.leap_stops[l] != CmaStop::none ? std::string("cma:") + to_string(s.leap_stops[l])
          : cfg_.population == 1               ? "descent"
          : cfg_.leap_iterations > 0           ? "iterations"
                                               : "episode_cap";
    return nlohmann::json{{"episodes", s.leap_episodes[l]},
                          {"descents", descents},
                          {"descent_steps", steps},
                          {"stale_stops", stale_in_leap},
                          {"first_loss", first},
                          {"best_loss", best},
                          {"end_loss", end},
                          {"ended", ended}};
  });
  return d;
}

std::unique_ptr<Optimizer> make_boleap(const BoLeapConfig& cfg) { return std::make_unique<BoLeap>(cfg); }

KnobTable boleap_knobs(BoLeapConfig& cfg) {
  KnobTable t("boleap");
  t.add("population", &cfg.population).add("sigma0", &cfg.sigma0);
  t.add("max_descent_steps", &cfg.max_descent_steps).add("patience", &cfg.patience);
  t.add("episodes_per_leap", &cfg.episodes_per_leap).add("leap_iterations", &cfg.leap_iterations);
  t.add("elite", &cfg.elite).add("lr", &cfg.adam.lr);
  t.add("plain_steps", &cfg.plain_steps).add("step_size", &cfg.step_size).add("adam_per_leap", &cfg.adam_per_leap);
  return t;
}

std::unique_ptr<Optimizer> make_boleap_with(const KnobSettings& settings) {
  return make_boleap(with_knobs(boleap_knobs, BoLeapConfig{}, settings));
}

}  // namespace dsb
