// CMA-ES (cmaes-library rules, IPOP restarts): constants against the reference table, one
// generation's update against the tutorial formulas, stop criteria, convergence on sphere-10 and
// rosenbrock-10, determinism, exact budget use, bounds, config validation.
#include "optimizers/cmaes.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "tests/support/function_objective.hpp"

namespace {

using dsb::CmaesConfig;
using dsb::CmaState;
using dsb::CmaStop;
using dsb::Rng;
using dsb::testing::FunctionObjective;

// physical box [-5, 5]^n: z = 5 x for x in [-1, 1]^n
double sphere5(std::span<const double> x) {
  double s = 0.0;
  for (double v : x) s += (5.0 * v) * (5.0 * v);
  return s;
}

double rosenbrock5(std::span<const double> x) {
  double s = 0.0;
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    const double a = 5.0 * x[i], b = 5.0 * x[i + 1];
    s += 100.0 * (b - a * a) * (b - a * a) + (1.0 - a) * (1.0 - a);
  }
  return s;
}

// runs cmaes until the budget is spent; the run must end by BudgetExhausted
void run_to_budget(dsb::Cmaes& opt, FunctionObjective& f, std::uint64_t seed) {
  Rng rng(seed);
  EXPECT_THROW(opt.minimize(f, rng), dsb::BudgetExhausted);
}

// 1-based index of the first episode with loss < thr, or -1
long first_below(const std::vector<double>& losses, double thr) {
  for (std::size_t i = 0; i < losses.size(); ++i)
    if (losses[i] < thr) return static_cast<long>(i) + 1;
  return -1;
}

// ---------------------------------------------------------------------------------------------
// constants

struct Row {
  int n, lambda, mu;
  double mu_eff, c1, cmu, c_sigma, d_sigma, c_c, chi_n;
  int funhist_term;
};

// Hansen's CMA-ES tutorial defaults (mu_eff to 4 decimals, the rest to 5)
const Row kTable[] = {
    {1, 4, 2, 1.4598, 0.29631, 0.02769, 0.46379, 1.46379, 0.68940, 0.79762, 18},
    {2, 6, 3, 2.0286, 0.15482, 0.05786, 0.44620, 1.44620, 0.62455, 1.25427, 20},
    {3, 7, 3, 2.2548, 0.09641, 0.05124, 0.41491, 1.41491, 0.55880, 1.59688, 23},
    {5, 8, 4, 2.6002, 0.04729, 0.03817, 0.36509, 1.36509, 0.45020, 2.12852, 29},
    {10, 10, 5, 3.1673, 0.01528, 0.02015, 0.28443, 1.28443, 0.29499, 3.08473, 40},
    {20, 12, 6, 3.7295, 0.00437, 0.00819, 0.19943, 1.19943, 0.17177, 4.41677, 60},
    {50, 15, 7, 4.5409, 0.00076, 0.00204, 0.10986, 1.10986, 0.07550, 7.03585, 110},
};

TEST(CmaesConstants, MatchReferenceTableToPrintedPrecision) {
  const double d4 = 0.5e-4 + 1e-12, d5 = 0.5e-5 + 1e-12;  // half a unit in the last printed digit
  for (const Row& r : kTable) {
    SCOPED_TRACE("n = " + std::to_string(r.n));
    EXPECT_EQ(dsb::cmaes_default_population(r.n), r.lambda);
    const auto k = dsb::cmaes_constants(r.n, r.lambda);
    EXPECT_EQ(k.lambda, r.lambda);
    EXPECT_EQ(k.mu, r.mu);
    EXPECT_NEAR(k.mu_eff, r.mu_eff, d4);
    EXPECT_NEAR(k.c1, r.c1, d5);
    EXPECT_NEAR(k.cmu, r.cmu, d5);
    EXPECT_NEAR(k.c_sigma, r.c_sigma, d5);
    EXPECT_NEAR(k.d_sigma, r.d_sigma, d5);
    EXPECT_NEAR(k.c_c, r.c_c, d5);
    EXPECT_NEAR(k.chi_n, r.chi_n, d5);
    EXPECT_EQ(k.funhist_term, r.funhist_term);
    EXPECT_EQ(static_cast<int>(k.weights.size()), r.lambda);
  }
}

TEST(CmaesConstants, N10ExactValues) {
  // n = 10, lambda = 10 from first principles: w'_1 = ln 5.5, mu_eff from the 5 positive w'
  const auto k = dsb::cmaes_constants(10, 10);
  double s = 0, s2 = 0;
  for (int i = 1; i <= 5; ++i) {
    const double w = std::log(5.5) - std::log(i);
    s += w;
    s2 += w * w;
  }
  EXPECT_NEAR(k.weights[0], std::log(5.5) / s, 1e-15);
  EXPECT_NEAR(k.mu_eff, s * s / s2, 1e-13);
  EXPECT_NEAR(k.c1, 2.0 / (11.3 * 11.3 + k.mu_eff), 1e-15);
  EXPECT_NEAR(k.chi_n, std::sqrt(10.0) * (1 - 1 / 40.0 + 1 / 2100.0), 1e-15);
}

TEST(CmaesConstants, PositiveWeightsSumToOneNegativeFollowAlphaMin) {
  // table rows plus larger / odd populations (odd lambda: w'_{mu+1} = 0 counts as non-negative)
  const std::pair<int, int> cases[] = {{1, 4}, {2, 6},   {3, 7},   {5, 8},    {10, 10},  {20, 12}, {50, 15},
                                       {2, 3}, {10, 21}, {10, 40}, {10, 640}, {400, 21}, {3, 2}};
  for (auto [n, lambda] : cases) {
    SCOPED_TRACE("n = " + std::to_string(n) + ", lambda = " + std::to_string(lambda));
    const auto k = dsb::cmaes_constants(n, lambda);
    // independent recomputation of w', mu_eff^-, alpha_min (eq. 49-53)
    std::vector<double> wp(lambda);
    for (int i = 0; i < lambda; ++i) wp[i] = std::log((lambda + 1) / 2.0) - std::log(i + 1.0);
    double s = 0, s2 = 0;
    for (int i = k.mu; i < lambda; ++i) {
      s += wp[i];
      s2 += wp[i] * wp[i];
    }
    const double mu_eff_minus = s * s / s2;
    const double alpha_min =
        std::min({1.0 + k.c1 / k.cmu, 1.0 + 2.0 * mu_eff_minus / (k.mu_eff + 2.0), (1.0 - k.c1 - k.cmu) / (n * k.cmu)});
    EXPECT_NEAR(k.alpha_min, alpha_min, 1e-12);
    // cmu capped at 1 - c1 - 1e-8
    EXPECT_LE(k.cmu, 1.0 - k.c1 - 1e-8 + 1e-16);

    double pos = 0, neg = 0, neg_wp = 0;
    int npos = 0;
    for (int i = 0; i < lambda; ++i) {
      if (wp[i] >= 0) {
        pos += k.weights[i];
        ++npos;
        EXPECT_GE(k.weights[i], 0.0);
      } else {
        neg += k.weights[i];
        neg_wp += std::abs(wp[i]);
        EXPECT_LT(k.weights[i], 0.0);
      }
    }
    EXPECT_EQ(npos, lambda - lambda / 2);  // mu positive (+ the zero one when lambda is odd)
    EXPECT_NEAR(pos, 1.0, 1e-14);
    EXPECT_NEAR(neg, -alpha_min, 1e-12);
    for (int i = 0; i < lambda; ++i) {
      if (wp[i] < 0) {
        EXPECT_NEAR(k.weights[i], alpha_min * wp[i] / neg_wp, 1e-14);
      }
    }
    for (int i = 1; i < lambda; ++i) EXPECT_LE(k.weights[i], k.weights[i - 1]);  // non-increasing
  }
  // large lambda: the -1e-8 cap on cmu is active (PR #49)
  const auto big = dsb::cmaes_constants(1, 100000);
  EXPECT_DOUBLE_EQ(big.cmu, 1.0 - big.c1 - 1e-8);
}

TEST(CmaesConstants, RejectsBadArguments) {
  EXPECT_THROW(dsb::cmaes_constants(0, 4), std::invalid_argument);
  EXPECT_THROW(dsb::cmaes_constants(3, 1), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// one generation by hand (C = I before the first tell, so C^-1/2 = I)

TEST(CmaState, FirstGenerationMatchesTutorialFormulas) {
  const int n = 3, lambda = 7;  // odd lambda: one zero weight
  Eigen::VectorXd m0(n);
  m0 << 0.1, -0.2, 0.3;
  const Eigen::VectorXd m0_copy = m0;
  const double sigma0 = 0.3;
  CmaState es(m0, sigma0, lambda, CmaesConfig{});
  Rng rng(7);
  std::vector<Eigen::VectorXd> xs;
  std::vector<double> fs;
  for (int k = 0; k < lambda; ++k) {
    xs.push_back(es.ask(rng));
    fs.push_back(sphere5(std::span<const double>(xs.back().data(), n)));
  }
  es.tell(xs, fs);
  EXPECT_EQ(es.generation(), 1);
  // the caller's mean is not aliased (library bug before v0.9.0)
  EXPECT_EQ(m0, m0_copy);

  const auto& k = es.constants();
  std::vector<int> order(lambda);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return fs[a] < fs[b]; });
  std::vector<Eigen::VectorXd> y(lambda);
  for (int i = 0; i < lambda; ++i) y[i] = (xs[order[i]] - m0) / sigma0;
  Eigen::VectorXd yw = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < k.mu; ++i) yw += k.weights[i] * y[i];

  // eq. 42: the new mean is the weighted recombination of the mu best points
  Eigen::VectorXd m1 = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < k.mu; ++i) m1 += k.weights[i] * xs[order[i]];
  EXPECT_LT((es.mean() - m1).cwiseAbs().maxCoeff(), 1e-14);

  // eq. 43, 44
  const double cs = k.c_sigma, cc = k.c_c;
  const Eigen::VectorXd ps = std::sqrt(cs * (2 - cs) * k.mu_eff) * yw;
  EXPECT_LT((es.p_sigma() - ps).cwiseAbs().maxCoeff(), 1e-13);
  const double sigma1 = sigma0 * std::exp(cs / k.d_sigma * (ps.norm() / k.chi_n - 1));
  EXPECT_NEAR(es.sigma(), sigma1, 1e-14);

  // h_sigma with exponent 2 (g + 1), g = 1 after the increment; eq. 45
  const double h = ps.norm() / std::sqrt(1 - std::pow(1 - cs, 4)) < (1.4 + 2.0 / (n + 1)) * k.chi_n ? 1 : 0;
  const Eigen::VectorXd pc = h * std::sqrt(cc * (2 - cc) * k.mu_eff) * yw;
  EXPECT_LT((es.p_c() - pc).cwiseAbs().maxCoeff(), 1e-13);

  // eq. 46, 47 with C = I
  double sum_w = 0;
  for (double w : k.weights) sum_w += w;
  Eigen::MatrixXd C = (1 + k.c1 * (1 - h) * cc * (2 - cc) - k.c1 - k.cmu * sum_w) * Eigen::MatrixXd::Identity(n, n);
  C += k.c1 * pc * pc.transpose();
  for (int i = 0; i < lambda; ++i) {
    const double w = k.weights[i] >= 0 ? k.weights[i] : k.weights[i] * n / (y[i].squaredNorm() + 1e-8);
    C += k.cmu * w * y[i] * y[i].transpose();
  }
  EXPECT_LT((es.cov() - C).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_FALSE(es.should_stop());
  EXPECT_EQ(es.stop_reason(), CmaStop::none);
}

TEST(CmaState, TellNeedsExactlyLambdaSolutions) {
  CmaState es(Eigen::VectorXd::Zero(4), 0.5, 8, CmaesConfig{});
  Rng rng(1);
  std::vector<Eigen::VectorXd> xs;
  std::vector<double> fs;
  for (int k = 0; k < 7; ++k) {
    xs.push_back(es.ask(rng));
    fs.push_back(1.0);
  }
  EXPECT_THROW(es.tell(xs, fs), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// stop criteria

TEST(CmaState, TolFunFiresRightAfterFunhistTermOnAFlatFunction) {
  // constant f: the best/worst history range is 0; TolFun needs g > funhist_term (= 40 for n = 10)
  CmaState es(Eigen::VectorXd::Zero(10), 0.5, 10, CmaesConfig{});
  ASSERT_EQ(es.constants().funhist_term, 40);
  Rng rng(3);
  for (int g = 1; g <= 41; ++g) {
    std::vector<Eigen::VectorXd> xs;
    std::vector<double> fs(10, 1.0);
    for (int k = 0; k < 10; ++k) xs.push_back(es.ask(rng));
    es.tell(xs, fs);
    if (g <= 40) {
      ASSERT_FALSE(es.should_stop()) << "generation " << g << ": " << dsb::to_string(es.stop_reason());
    } else {
      EXPECT_TRUE(es.should_stop());
      EXPECT_EQ(es.stop_reason(), CmaStop::tolfun);
    }
  }
}

TEST(Cmaes, IpopRestartsDoublePopulationOn2DSphere) {
  FunctionObjective f(2, 20000, sphere5);
  dsb::Cmaes opt;
  run_to_budget(opt, f, 11);
  const auto& st = opt.last_run();
  ASSERT_GE(st.restarts(), 2);
  EXPECT_EQ(st.populations[0], 6);  // 4 + floor(3 ln 2)
  for (std::size_t i = 1; i < st.populations.size(); ++i) EXPECT_EQ(st.populations[i], 2 * st.populations[i - 1]);
  ASSERT_EQ(st.stops.size(), st.populations.size() - 1);  // the last instance was cut by the budget
  for (CmaStop s : st.stops) {
    EXPECT_NE(s, CmaStop::none);
    EXPECT_NE(s, CmaStop::numerical);
  }
  EXPECT_LT(f.best(), 1e-12);
}

TEST(Cmaes, WithoutIpopReturnsEarlyOnStop) {
  FunctionObjective f(2, 100000, sphere5);
  CmaesConfig cfg;
  cfg.ipop = false;
  dsb::Cmaes opt(cfg);
  Rng rng(5);
  EXPECT_NO_THROW(opt.minimize(f, rng));
  EXPECT_LT(f.used(), 100000);
  EXPECT_EQ(f.used() % 6, 0);  // whole generations of lambda = 6
  EXPECT_EQ(opt.last_run().populations.size(), 1u);
  ASSERT_EQ(opt.last_run().stops.size(), 1u);
  EXPECT_NE(opt.last_run().stops[0], CmaStop::none);
  EXPECT_EQ(opt.last_run().generations * 6, f.used());
  EXPECT_LT(f.best(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// convergence, physical box [-5, 5]^10, default config (sigma0 0.5, IPOP). Not cherry-picked: seeds
// 1..40 were all tried for both functions and all reach 1e-8 within these budgets; the tests run
// seeds 1..8. Measured evaluations to the first loss < 1e-8:
//   sphere-10:     seeds 1..8: 1343 1315 1476 1409 1375 1402 1432 1408 (1..40: 1232-1631)
//   rosenbrock-10: seeds 1..8: 5037 5632 5196 5386 6493 5455 5120 5645 (1..40: 4267-6493, except
//                  seed 39: 14605, after the first instance stalled and IPOP restarted)

// on seeds 1..8, default CMA-ES on fn in 10-D uses the whole budget, ends below 1e-8 and first
// gets there before episode `hit_before`
void expect_below_1e8_on_eight_seeds(FunctionObjective::Fn fn, std::int64_t budget, long hit_before) {
  for (std::uint64_t seed : {1, 2, 3, 4, 5, 6, 7, 8}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    FunctionObjective f(10, budget, fn);
    dsb::Cmaes opt;
    run_to_budget(opt, f, seed);
    EXPECT_EQ(f.used(), budget);
    EXPECT_LT(f.best(), 1e-8);
    const long hit = first_below(f.losses(), 1e-8);
    EXPECT_GT(hit, 0);
    EXPECT_LT(hit, hit_before);
  }
}

TEST(Cmaes, Sphere10Below1e8Within6000Evaluations) {
  expect_below_1e8_on_eight_seeds(sphere5, 6000, 3000);  // measured 1315-1476 on these seeds
}

TEST(Cmaes, Rosenbrock10Below1e8Within30000Evaluations) {
  expect_below_1e8_on_eight_seeds(rosenbrock5, 30000, 15000);  // measured 5037-6493 on these seeds
}

TEST(Cmaes, FailedEpisodesCountAsWorst) {
  // NaN (a blown-up simulation) for x0 > 0.5: recorded as +inf, never selected; still converges
  auto fn = [](std::span<const double> x) {
    return x[0] > 0.5 ? std::numeric_limits<double>::quiet_NaN() : sphere5(x);
  };
  FunctionObjective f(5, 4000, fn);
  dsb::Cmaes opt(CmaesConfig{.sigma0 = 1.0});
  run_to_budget(opt, f, 2);
  long failed = 0;
  for (double l : f.losses()) failed += std::isnan(l) ? 1 : 0;
  EXPECT_GT(failed, 0);
  EXPECT_LT(f.best(), 1e-8);
}

// ---------------------------------------------------------------------------------------------
// determinism, budget, bounds

TEST(Cmaes, SameSeedBitIdenticalDifferentSeedDifferent) {
  auto run = [](std::uint64_t seed) {
    FunctionObjective f(10, 2500, rosenbrock5);
    dsb::Cmaes opt;
    Rng rng(seed);
    try {
      opt.minimize(f, rng);
    } catch (const dsb::BudgetExhausted&) {}
    return f.losses();
  };
  const auto a = run(42), b = run(42), c = run(43);
  ASSERT_EQ(a.size(), 2500u);
  ASSERT_EQ(b.size(), a.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
  ASSERT_EQ(c.size(), a.size());
  EXPECT_NE(std::memcmp(a.data(), c.data(), a.size() * sizeof(double)), 0);
  EXPECT_NE(a[0], c[0]);
}

TEST(Cmaes, UsesExactlyTheBudgetAndStaysInTheBox) {
  // B = 1003 is not a multiple of lambda = 10: the last generation is cut by BudgetExhausted
  int calls = 0;
  FunctionObjective f(10, 1003, [&](std::span<const double> x) {
    ++calls;
    return rosenbrock5(x);
  });
  dsb::Cmaes opt;
  Rng rng(9);
  EXPECT_THROW(opt.minimize(f, rng), dsb::BudgetExhausted);
  EXPECT_EQ(f.used(), 1003);
  EXPECT_EQ(f.losses().size(), 1003u);
  // the budget is checked before the function runs: the refused 1004th call never simulates
  EXPECT_EQ(calls, 1003);
  for (const auto& p : f.points())
    for (double v : p) {
      EXPECT_GE(v, -1.0);
      EXPECT_LE(v, 1.0);
    }
  EXPECT_EQ(opt.last_run().generations, 100);
}

TEST(Cmaes, HugeSigmaResampleThenClipKeepsCandidatesInTheBox) {
  FunctionObjective f(10, 600, sphere5);
  dsb::Cmaes opt(CmaesConfig{.sigma0 = 50.0});
  run_to_budget(opt, f, 4);
  long on_bound = 0;
  for (const auto& p : f.points())
    for (double v : p) {
      ASSERT_GE(v, -1.0);
      ASSERT_LE(v, 1.0);
      on_bound += (v == -1.0 || v == 1.0) ? 1 : 0;
    }
  EXPECT_GT(on_bound, 0);  // the clip fallback was used

  // directly: with sigma 50 nearly every draw is outside, so the 101st draw gets clipped
  CmaState es(Eigen::VectorXd::Zero(10), 50.0, 10, CmaesConfig{});
  Rng rng(8);
  int clipped = 0;
  for (int k = 0; k < 1000; ++k) {
    const Eigen::VectorXd x = es.ask(rng);
    ASSERT_LE(x.cwiseAbs().maxCoeff(), 1.0);
    clipped += x.cwiseAbs().maxCoeff() == 1.0 ? 1 : 0;
  }
  EXPECT_EQ(clipped, 1000);

  // small sigma: resampling alone suffices, nothing lands exactly on the bound
  CmaState small(Eigen::VectorXd::Zero(10), 0.2, 10, CmaesConfig{});
  for (int k = 0; k < 1000; ++k) ASSERT_LT(small.ask(rng).cwiseAbs().maxCoeff(), 1.0);
}

// ---------------------------------------------------------------------------------------------
// config

TEST(CmaesConfig, ValidationNamesTheField) {
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    CmaesConfig cfg;
    cfg.sigma0 = bad;
    try {
      cfg.validate();
      ADD_FAILURE() << "sigma0 = " << bad << " accepted";
    } catch (const dsb::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("sigma0"), std::string::npos) << e.what();
    }
    EXPECT_THROW(dsb::make_cmaes(cfg), dsb::ConfigError);
  }
  CmaesConfig pop;
  pop.population = 1;
  try {
    pop.validate();
    ADD_FAILURE() << "population = 1 accepted";
  } catch (const dsb::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("population"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(CmaesConfig{}.validate());
}

TEST(CmaesConfig, OptimizerIdentityAndConfigJson) {
  const auto opt = dsb::make_cmaes();
  EXPECT_EQ(opt->name(), "cmaes");
  EXPECT_FALSE(opt->needs_gradient());
  const auto j = opt->config();
  EXPECT_EQ(j.at("sigma0").get<double>(), 0.5);
  EXPECT_EQ(j.at("population").get<int>(), 0);
  EXPECT_EQ(j.at("max_resampling").get<int>(), 100);
  EXPECT_EQ(j.at("ipop").get<bool>(), true);
  EXPECT_EQ(j.at("ipop_factor").get<double>(), 2.0);
  EXPECT_EQ(j.at("tolfun").get<double>(), 1e-12);
  EXPECT_EQ(j.at("tolx_factor").get<double>(), 1e-12);
  EXPECT_EQ(j.at("tolxup").get<double>(), 1e4);
  EXPECT_EQ(j.at("condition_max").get<double>(), 1e14);
}

}  // namespace
