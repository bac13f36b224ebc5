// Building blocks of the RL baselines (optimizers/rl/): Mlp forward/backward against central
// differences and an Eigen reference forward, the two initialisations, NetworkAdam, clip_grad_norm,
// polyak_update, the diagonal and the tanh-squashed Gaussian. Every test prints its measured errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string_view>
#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Dense>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "optimizers/rl/gaussian.hpp"
#include "optimizers/rl/mlp.hpp"
#include "optimizers/rl/network_adam.hpp"
#include "support/gradient_vs_differences.hpp"

using namespace dsb;

namespace {

Eigen::MatrixXd normal_matrix(int rows, int cols, Rng& rng) {
  Eigen::MatrixXd m(rows, cols);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) m(i, j) = rng.normal();
  return m;
}

// independent reference forward with Eigen products on the documented layout; also returns the
// smallest |pre-activation| of the hidden layers (distance to the relu kink)
Eigen::MatrixXd reference_forward(const Mlp& net, const Eigen::MatrixXd& x, double* min_abs_z) {
  Eigen::MatrixXd a = x;
  double mz = INFINITY;
  const int L = net.layer_count();
  for (int l = 0; l < L; ++l) {
    const int rows = net.sizes()[l + 1], cols = net.sizes()[l];
    Eigen::Map<const Eigen::MatrixXd> w(net.params().data() + net.weight_offset(l), rows, cols);
    Eigen::Map<const Eigen::VectorXd> b(net.params().data() + net.bias_offset(l), rows);
    Eigen::MatrixXd z = (w * a).colwise() + b;
    if (l == L - 1) return z;
    mz = std::min(mz, z.cwiseAbs().minCoeff());
    a = net.activation() == Activation::tanh ? Eigen::MatrixXd(z.array().tanh()) : Eigen::MatrixXd(z.cwiseMax(0.0));
    if (min_abs_z) *min_abs_z = mz;
  }
  return a;
}

// L = sum(R .* net(x)); analytic dL/dparams, dL/dx vs central differences with step h
void check_mlp_gradient(Mlp& net, const Eigen::MatrixXd& x, const Eigen::MatrixXd& r, double h, const char* name,
                        double tol_normwise, double tol_max) {
  auto loss = [&](const Eigen::MatrixXd& xx) { return (r.array() * net.forward(xx).array()).sum(); };
  MlpCache cache;
  net.forward(x, &cache);
  std::vector<double> ga(net.param_count(), 0.0);
  Eigen::MatrixXd dx;
  net.backward(cache, r, ga, &dx);

  std::vector<double> gf(net.param_count());
  auto p = net.params();
  for (std::size_t i = 0; i < p.size(); ++i) gf[i] = dsb::testing::central_difference(p[i], h, [&] { return loss(x); });
  std::vector<double> xa(dx.data(), dx.data() + dx.size()), xf(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Eigen::MatrixXd xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    xf[i] = (loss(xp) - loss(xm)) / (2 * h);
  }
  const dsb::testing::GradientError ep = dsb::testing::gradient_error(ga, gf),
                                    ex = dsb::testing::gradient_error(xa, xf);
  std::printf("%s: %zu params, h %.0e: param grad normwise %.3e max %.3e; input grad normwise %.3e max %.3e\n", name,
              net.param_count(), h, ep.normwise, ep.max_rel, ex.normwise, ex.max_rel);
  EXPECT_LT(ep.normwise, tol_normwise);
  EXPECT_LT(ep.max_rel, tol_max);
  EXPECT_LT(ex.normwise, tol_normwise);
  EXPECT_LT(ex.max_rel, tol_max);

  // backward adds to grad (a second pass gives 2 ga up to the rounding of the running sums);
  // an empty grad span gives the same dL/dx bit for bit
  std::vector<double> g2 = ga;
  net.backward(cache, r, g2);
  double acc = 0, gmax = 0;
  for (std::size_t i = 0; i < ga.size(); ++i) {
    acc = std::max(acc, std::abs(g2[i] - 2 * ga[i]));
    gmax = std::max(gmax, std::abs(ga[i]));
  }
  EXPECT_LT(acc, 1e-14 * gmax);
  Eigen::MatrixXd dx2;
  net.backward(cache, r, {}, &dx2);
  EXPECT_EQ((dx2 - dx).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace

TEST(RlMlp, LayoutAndForwardMatchEigenReference) {
  Rng rng(11);
  Mlp net({5, 64, 64, 64, 3}, Activation::tanh);
  EXPECT_EQ(net.param_count(), 5u * 64 + 64 + 2 * (64 * 64 + 64) + 64 * 3 + 3);
  EXPECT_EQ(net.bias_offset(0), 320u);
  EXPECT_EQ(net.weight_offset(1), 384u);
  init_torch_default(net, rng);
  const Eigen::MatrixXd x = normal_matrix(5, 4, rng);
  const Eigen::MatrixXd y = net.forward(x);
  const Eigen::MatrixXd yr = reference_forward(net, x, nullptr);
  const double err = (y - yr).cwiseAbs().maxCoeff() / yr.cwiseAbs().maxCoeff();
  std::printf("forward vs Eigen reference: max rel diff %.3e\n", err);
  EXPECT_LT(err, 1e-13);
  // the single-sample path is the batch column, bit for bit
  for (int s = 0; s < 4; ++s) EXPECT_EQ((net.forward_one(x.col(s)) - y.col(s)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_THROW(net.forward(Eigen::MatrixXd::Zero(4, 2)), std::invalid_argument);
  EXPECT_THROW(Mlp({5}, Activation::tanh), ConfigError);
  EXPECT_THROW(Mlp({5, 0, 2}, Activation::relu), ConfigError);
}

// Central differences of a smooth net: error ~ h^2 |L'''| / 6 + eps_mach |L| / h; with h = 1e-5 and
// |L| ~ 1 both are ~1e-10, against gradient entries up to ~1.
TEST(RlMlp, BackwardTanhMatchesCentralDifferences) {
  Rng rng(3);
  Mlp net({5, 64, 64, 64, 3}, Activation::tanh);
  init_orthogonal(net, 1.0, rng);
  const Eigen::MatrixXd x = normal_matrix(5, 4, rng), r = normal_matrix(3, 4, rng);
  check_mlp_gradient(net, x, r, 1e-5, "tanh {5,64,64,64,3} batch 4", 1e-8, 1e-8);
}

// A relu net is linear in each single parameter and input while no pre-activation changes sign,
// so central differences have no truncation error there: only rounding, eps_mach |L| / h ~ 1e-10
// for h = 1e-6. A step of 1e-6 moves any pre-activation by far less than 1e-3, so points with
// every |z| > 1e-3 keep their activation pattern.
TEST(RlMlp, BackwardReluMatchesCentralDifferences) {
  for (std::uint64_t seed = 1; seed < 200; ++seed) {
    Rng rng(seed);
    Mlp net({5, 64, 64, 64, 3}, Activation::relu);
    init_torch_default(net, rng);
    const Eigen::MatrixXd x = normal_matrix(5, 4, rng), r = normal_matrix(3, 4, rng);
    double min_z = 0;
    reference_forward(net, x, &min_z);
    if (min_z < 1e-3) continue;
    std::printf("relu point: seed %llu, smallest |pre-activation| %.3e\n", (unsigned long long)seed, min_z);
    check_mlp_gradient(net, x, r, 1e-6, "relu {5,64,64,64,3} batch 4", 1e-8, 1e-8);
    return;
  }
  FAIL() << "no seed below 200 gives a point away from the relu kinks";
}

TEST(RlMlp, OrthogonalInit) {
  Rng rng(5);
  Mlp net({5, 64, 64, 3}, Activation::tanh);
  init_orthogonal(net, 0.01, rng);
  double worst = 0;
  for (int l = 0; l < net.layer_count(); ++l) {
    const Eigen::MatrixXd w = net.weight(l);
    const double gain = l == net.layer_count() - 1 ? 0.01 : std::sqrt(2.0);
    // tall: W^T W = gain^2 I; wide: W W^T = gain^2 I; square: both
    Eigen::MatrixXd g = w.rows() >= w.cols() ? Eigen::MatrixXd(w.transpose() * w) : Eigen::MatrixXd(w * w.transpose());
    const double e = (g - gain * gain * Eigen::MatrixXd::Identity(g.rows(), g.cols())).cwiseAbs().maxCoeff();
    worst = std::max(worst, e);
    EXPECT_LT(e, 1e-12) << "layer " << l;
    if (w.rows() == w.cols()) {
      EXPECT_LT((w * w.transpose() - gain * gain * Eigen::MatrixXd::Identity(w.rows(), w.rows())).cwiseAbs().maxCoeff(),
                1e-12);
    }
    EXPECT_EQ(net.bias(l).cwiseAbs().maxCoeff(), 0.0);
  }
  std::printf("orthogonal init {5,64,64,3}: max |W W^T - gain^2 I| %.3e\n", worst);

  // deterministic per seed, different per seed
  Mlp a({5, 64, 64, 3}, Activation::tanh), b = a, c = a;
  Rng r1(7), r2(7), r3(8);
  init_orthogonal(a, 0.01, r1);
  init_orthogonal(b, 0.01, r2);
  init_orthogonal(c, 0.01, r3);
  EXPECT_TRUE(std::equal(a.params().begin(), a.params().end(), b.params().begin()));
  EXPECT_FALSE(std::equal(a.params().begin(), a.params().end(), c.params().begin()));

  // the same construction through Eigen's HouseholderQR, on the same Gaussian draws
  double qr_diff = 0;
  for (auto [rows, cols] : {std::pair{64, 5}, std::pair{64, 64}, std::pair{3, 64}}) {
    Rng ra(21), rb(21);
    const Eigen::MatrixXd w = orthogonal_matrix(rows, cols, 1.5, ra);
    Eigen::MatrixXd g(rows, cols);
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < cols; ++j) g(i, j) = rb.normal();
    const bool wide = rows < cols;
    const Eigen::MatrixXd t = wide ? Eigen::MatrixXd(g.transpose()) : g;
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(t);
    Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(t.rows(), t.cols());
    const Eigen::MatrixXd rr = qr.matrixQR().triangularView<Eigen::Upper>();
    for (Eigen::Index j = 0; j < q.cols(); ++j) q.col(j) *= rr(j, j) > 0 ? 1.5 : -1.5;
    const Eigen::MatrixXd we = wide ? Eigen::MatrixXd(q.transpose()) : q;
    qr_diff = std::max(qr_diff, (w - we).cwiseAbs().maxCoeff());
  }
  std::printf("orthogonal_matrix vs Eigen HouseholderQR (sign-fixed): max diff %.3e\n", qr_diff);
  EXPECT_LT(qr_diff, 1e-12);
}

// U(-b, b) has mean 0, variance b^2/3 and Var(X^2) = b^4 (1/5 - 1/9) = 4 b^4 / 45, so over N draws
// the sample mean has standard deviation b / sqrt(3 N) and the sample variance about
// b^2 sqrt(4/45) / sqrt(N). Bounds of 5 standard deviations (fixed seed: a deterministic check
// whose tolerance is set by that spread).
TEST(RlMlp, TorchDefaultInit) {
  Rng rng(9);
  Mlp net({256, 256, 5}, Activation::relu);
  init_torch_default(net, rng);
  for (int l = 0; l < net.layer_count(); ++l) {
    const double b = 1.0 / std::sqrt(double(net.sizes()[l]));
    EXPECT_LE(net.weight(l).maxCoeff(), b);
    EXPECT_GE(net.weight(l).minCoeff(), -b);
    EXPECT_LE(net.bias(l).cwiseAbs().maxCoeff(), b);
  }
  const Eigen::MatrixXd w = net.weight(0);
  const double b = 1.0 / 16.0, n = double(w.size());
  const double mean = w.mean();
  const double var = (w.array() - mean).square().sum() / (n - 1);
  const double sd_mean = b / std::sqrt(3 * n), sd_var = b * b * std::sqrt(4.0 / 45.0) / std::sqrt(n);
  std::printf("torch init 256x256 (b = 1/16): mean %.3e (%.2f sd), variance %.6e vs b^2/3 = %.6e (%.2f sd)\n", mean,
              mean / sd_mean, var, b * b / 3, (var - b * b / 3) / sd_var);
  EXPECT_LT(std::abs(mean), 5 * sd_mean);
  EXPECT_LT(std::abs(var - b * b / 3), 5 * sd_var);
}

// Two Adam steps by hand (lr 0.1, b1 0.9, b2 0.999, eps 1e-5), p = (1, -2), g1 = (0.5, -1),
// g2 = (0.1, 0.3):
//   t=1: m = (0.05, -0.1), v = (0.00025, 0.001), mhat = g1, vhat = g1^2,
//        p = (1 - 0.1 * 0.5/0.50001, -2 + 0.1 * 1/1.00001) = (0.90000199996..., -1.90000099999...)
//   t=2: m = 0.9 m + 0.1 g2 = (0.055, -0.06), v = 0.999 v + 0.001 g2^2 = (0.00025975, 0.001089),
//        c1 = 0.19, c2 = 0.001999; p0 -= 0.1 (0.055/0.19) / (sqrt(0.00025975/0.001999) + 1e-5)
//        -> 0.81970012980445769, p1 -= 0.1 (-0.06/0.19) / (sqrt(0.001089/0.001999) + 1e-5)
//        -> -1.8572167205040216 (40-digit decimal arithmetic)
TEST(RlMlp, NetworkAdamClipPolyakByHand) {
  AdamConfig cfg;
  cfg.lr = 0.1;
  cfg.eps = 1e-5;
  NetworkAdam adam(cfg, 2);
  std::vector<double> p = {1.0, -2.0};
  adam.step(p, std::vector<double>{0.5, -1.0});
  const double e1[2] = {0.90000199996000080, -1.9000009999900001};
  adam.step(p, std::vector<double>{0.1, 0.3});
  const double e2[2] = {0.81970012980445769, -1.8572167205040216};
  // (step-1 values are checked through step 2; recompute them on a fresh optimizer)
  NetworkAdam a1(cfg, 2);
  std::vector<double> q = {1.0, -2.0};
  a1.step(q, std::vector<double>{0.5, -1.0});
  double worst = 0;
  for (int i = 0; i < 2; ++i) {
    worst = std::max({worst, std::abs(q[i] - e1[i]) / std::abs(e1[i]), std::abs(p[i] - e2[i]) / std::abs(e2[i])});
  }
  std::printf("adam two steps: max rel error vs hand values %.3e\n", worst);
  EXPECT_LT(worst, 1e-15);
  EXPECT_EQ(adam.steps(), 2);
  EXPECT_THROW(adam.step(p, std::vector<double>{1.0}), std::invalid_argument);

  // clip_grad_norm: (3, 4) has norm 5 > 1 -> times 1/(5 + 1e-6); (0.3, 0.4) is left alone
  std::vector<double> g = {3.0, 4.0};
  EXPECT_EQ(clip_grad_norm(g, 1.0), 5.0);
  const double ce = std::max(std::abs(g[0] - 0.59999988000002400) / 0.6, std::abs(g[1] - 0.79999984000003200) / 0.8);
  std::printf("clip_grad_norm: rel error %.3e\n", ce);
  EXPECT_LT(ce, 1e-15);
  std::vector<double> small = {0.3, 0.4};
  clip_grad_norm(small, 1.0);
  EXPECT_EQ(small[0], 0.3);
  EXPECT_EQ(small[1], 0.4);

  // polyak: (1, 2) toward (3, -1) with tau 0.005 -> (1.01, 1.985)
  std::vector<double> t = {1.0, 2.0};
  polyak_update(t, std::vector<double>{3.0, -1.0}, 0.005);
  const double pe = std::max(std::abs(t[0] - 1.01), std::abs(t[1] - 1.985));
  std::printf("polyak_update: abs error %.3e\n", pe);
  EXPECT_LT(pe, 1e-15);
}

// log N and entropy against the textbook forms; derivatives against central differences (h 1e-6:
// error ~ h^2 + 1e-16 / h ~ 1e-10 relative)
TEST(RlMlp, DiagGaussian) {
  const std::vector<double> a = {0.3, -1.2, 2.0}, m = {0.1, 0.5, -0.4}, ls = {-0.7, 0.4, 0.0};
  std::vector<double> dm_(3), dls(3);
  const double lp = diag_gaussian_log_prob(a, m, ls, dm_, dls);
  double ref = 0, href = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = std::exp(ls[i]);
    ref += std::log(std::exp(-(a[i] - m[i]) * (a[i] - m[i]) / (2 * s * s)) / (s * std::sqrt(2 * M_PI)));
    href += 0.5 * std::log(2 * M_PI * M_E * s * s);
  }
  std::vector<double> dh(3);
  const double h = diag_gaussian_entropy(ls, dh);
  std::printf("diag gaussian: log_prob %.17g vs %.17g (diff %.3e), entropy %.17g vs %.17g (diff %.3e)\n", lp, ref,
              lp - ref, h, href, h - href);
  EXPECT_NEAR(lp, ref, 1e-14);
  EXPECT_NEAR(h, href, 1e-14);

  const double step = 1e-6;
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    auto mp = m, mm = m, lsp = ls, lsm = ls;
    mp[i] += step;
    mm[i] -= step;
    lsp[i] += step;
    lsm[i] -= step;
    const double fm = (diag_gaussian_log_prob(a, mp, ls) - diag_gaussian_log_prob(a, mm, ls)) / (2 * step);
    const double fl = (diag_gaussian_log_prob(a, m, lsp) - diag_gaussian_log_prob(a, m, lsm)) / (2 * step);
    const double fh = (diag_gaussian_entropy(lsp) - diag_gaussian_entropy(lsm)) / (2 * step);
    worst = std::max({worst, std::abs(fm - dm_[i]) / std::abs(dm_[i]), std::abs(fl - dls[i]) / std::abs(dls[i]),
                      std::abs(fh - dh[i])});
  }
  std::printf("diag gaussian derivatives vs central differences: max rel error %.3e\n", worst);
  EXPECT_LT(worst, 1e-8);
}

// Density of a = tanh(u), u ~ N(m, s^2), by SB3's formula p(a) = N(u) / (1 - a^2 + d), d = 1e-6.
// In u-space, int p(a) da = E[(1 - a^2) / (1 - a^2 + d)] = 1 - E[d cosh^2 u / (1 + d cosh^2 u)],
// so the deficit is D = d E[cosh^2 u] - r with 0 <= r <= d^2 E[cosh^4 u] (x - x^2 <= x/(1+x) <= x
// for x = d cosh^2 u >= 0), where
// E[cosh^2 u] = (1 + cosh(2m) e^{2 s^2}) / 2 and E[cosh^4 u] = (3 + 4 cosh(2m) e^{2s^2} + cosh(4m) e^{8s^2}) / 8.
// Quadrature: Simpson in e = (u - m)/s over [-12, 12] with step 1e-3 (truncation ~1e-32, Simpson
// error far below 1e-12 for this smooth integrand).
TEST(RlMlp, SquashedGaussianDensityIntegrates) {
  for (auto [m, ls] : {std::pair{0.0, 0.0}, std::pair{0.5, -0.5}, std::pair{-1.0, -1.0}}) {
    const double s = std::exp(ls);
    const int n = 24000;
    const double lo = -12.0, step = 24.0 / n;
    double integral = 0;
    for (int k = 0; k <= n; ++k) {
      const double e = lo + k * step;
      const double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
      const SquashedGaussian g =
          squashed_gaussian(std::vector<double>{m}, std::vector<double>{ls}, std::vector<double>{e});
      // p(a) da/de, da/de = (1 - a^2) s
      integral += w * std::exp(g.log_prob) * g.da_dmean[0] * s;
    }
    integral *= step / 3;
    const double d = kSquashEpsilon, ec2 = std::cosh(2 * m) * std::exp(2 * s * s);
    const double predicted = d * (1 + ec2) / 2;
    const double r_bound = d * d * (3 + 4 * ec2 + std::cosh(4 * m) * std::exp(8 * s * s)) / 8;
    const double deficit = 1 - integral;
    std::printf(
        "squashed density m %.1f log_std %.1f: integral 1 - %.6e, predicted deficit %.6e, diff %.3e (bound %.3e)\n", m,
        ls, deficit, predicted, deficit - predicted, r_bound + 1e-12);
    // 0 <= predicted - deficit = r <= d^2 E[cosh^4 u], plus 1e-12 for quadrature and rounding
    EXPECT_LE(deficit, predicted + 1e-12);
    EXPECT_GE(deficit, predicted - r_bound - 1e-12);
    EXPECT_GT(deficit, 0.0);
  }
}

// Reparameterised derivatives at a fixed e vs central differences (h 1e-6), the chain rule of
// squashed_gaussian_backward vs differences of L = alpha log pi + w . a, and the log-std clamp.
TEST(RlMlp, SquashedGaussianDerivatives) {
  const std::vector<double> m = {0.3, -1.1, 0.05}, ls = {-0.4, 0.2, -2.0}, e = {0.7, -1.3, 2.1};
  const SquashedGaussian g = squashed_gaussian(m, ls, e);
  const double h = 1e-6, alpha = 0.2;
  const std::vector<double> w = {-0.8, 1.5, 0.4};
  auto loss = [&](const SquashedGaussian& s) {
    double l = alpha * s.log_prob;
    for (int i = 0; i < 3; ++i) l += w[i] * s.a[i];
    return l;
  };
  std::vector<double> dlm(3), dlls(3);
  squashed_gaussian_backward(g, w, alpha, dlm, dlls);
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    auto mp = m, mm = m, lp = ls, lm = ls;
    mp[i] += h;
    mm[i] -= h;
    lp[i] += h;
    lm[i] -= h;
    const SquashedGaussian gmp = squashed_gaussian(mp, ls, e), gmm = squashed_gaussian(mm, ls, e);
    const SquashedGaussian glp = squashed_gaussian(m, lp, e), glm = squashed_gaussian(m, lm, e);
    auto rel = [](double an, double fd) { return std::abs(an - fd) / std::max(std::abs(an), 1e-3); };
    worst = std::max({worst, rel(g.da_dmean[i], (gmp.a[i] - gmm.a[i]) / (2 * h)),
                      rel(g.da_dlog_std[i], (glp.a[i] - glm.a[i]) / (2 * h)),
                      rel(g.dlogp_dmean[i], (gmp.log_prob - gmm.log_prob) / (2 * h)),
                      rel(g.dlogp_dlog_std[i], (glp.log_prob - glm.log_prob) / (2 * h)),
                      rel(dlm[i], (loss(gmp) - loss(gmm)) / (2 * h)), rel(dlls[i], (loss(glp) - loss(glm)) / (2 * h))});
  }
  std::printf("squashed gaussian derivatives vs central differences: max rel error %.3e\n", worst);
  EXPECT_LT(worst, 1e-7);

  // log_std outside [-20, 2] is clamped: same draw as at the bound, zero derivative
  const SquashedGaussian hi =
      squashed_gaussian(std::vector<double>{0.1}, std::vector<double>{2.5}, std::vector<double>{0.3});
  const SquashedGaussian at =
      squashed_gaussian(std::vector<double>{0.1}, std::vector<double>{2.0}, std::vector<double>{0.3});
  const SquashedGaussian lo =
      squashed_gaussian(std::vector<double>{0.1}, std::vector<double>{-25.0}, std::vector<double>{0.3});
  EXPECT_EQ(hi.log_prob, at.log_prob);
  EXPECT_EQ(hi.a[0], at.a[0]);
  EXPECT_EQ(hi.da_dlog_std[0], 0.0);
  EXPECT_EQ(hi.dlogp_dlog_std[0], 0.0);
  EXPECT_EQ(lo.dlogp_dlog_std[0], 0.0);
  EXPECT_NE(at.dlogp_dlog_std[0], 0.0);

  // sampling draws e from the Rng and nothing else
  Rng r1(4), r2(4);
  const SquashedGaussian sa = squashed_gaussian_sample(m, ls, r1);
  const std::vector<double> e2 = {r2.normal(), r2.normal(), r2.normal()};
  const SquashedGaussian sb = squashed_gaussian(m, ls, e2);
  EXPECT_EQ(sa.log_prob, sb.log_prob);
  EXPECT_EQ(sa.a, sb.a);
}

// Bits pinned: both inits, a SAC-sized forward and backward (inner dimension 256, where Eigen's
// GEMM would block by the CPU's L1 size) and an Adam step, hashed. A different value on another
// x86-64 CPU or compiler flag set means the arithmetic is not what the header promises.
TEST(RlMlp, GoldenDigest) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  auto add = [&h](const double* p, std::size_t n) {
    h = fnv1a64(std::string_view(reinterpret_cast<const char*>(p), n * sizeof(double)), h);
  };
  Rng rng(2024);
  Mlp ppo({8, 64, 64, 2}, Activation::tanh);
  init_orthogonal(ppo, 0.01, rng);
  add(ppo.params().data(), ppo.param_count());
  Mlp sac({10, 256, 256, 1}, Activation::relu);
  init_torch_default(sac, rng);
  add(sac.params().data(), sac.param_count());
  const Eigen::MatrixXd x = normal_matrix(10, 256, rng);
  MlpCache cache;
  const Eigen::MatrixXd y = sac.forward(x, &cache);
  add(y.data(), y.size());
  std::vector<double> g(sac.param_count(), 0.0);
  Eigen::MatrixXd dx;
  sac.backward(cache, Eigen::MatrixXd::Constant(1, 256, 1.0 / 256), g, &dx);
  add(g.data(), g.size());
  add(dx.data(), dx.size());
  AdamConfig cfg;
  cfg.lr = 3e-4;
  NetworkAdam adam(cfg, sac.param_count());
  clip_grad_norm(g, 0.5);
  adam.step(sac.params(), g);
  add(sac.params().data(), sac.param_count());
  std::printf("golden digest %016llx\n", (unsigned long long)h);
  EXPECT_EQ(h, 0x768c7671edbdd16aULL);
}
