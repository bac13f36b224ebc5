#include "optimizers/rl/gaussian.hpp"

#include <initializer_list>
#include <stdexcept>
#include <string>

#include "common/det_math.hpp"

namespace dsb {

namespace {

constexpr double kHalfLog2Pi = 0.91893853320467274178;  // log(2 pi) / 2

void check_sizes(const char* who, std::size_t d, std::initializer_list<std::size_t> sizes) {
  for (std::size_t n : sizes)
    if (n != d)
      throw std::invalid_argument(std::string(who) + ": all vectors must have the action dimension " +
                                  std::to_string(d));
}

void check_optional(const char* who, std::size_t d, std::span<double> out) {
  if (!out.empty() && out.size() != d)
    throw std::invalid_argument(std::string(who) + ": a derivative span must be empty or d long");
}

}  // namespace

double diag_gaussian_log_prob(std::span<const double> a, std::span<const double> mean, std::span<const double> log_std,
                              std::span<double> d_mean, std::span<double> d_log_std) {
  const std::size_t d = mean.size();
  check_sizes("diag_gaussian_log_prob", d, {a.size(), log_std.size()});
  check_optional("diag_gaussian_log_prob", d, d_mean);
  check_optional("diag_gaussian_log_prob", d, d_log_std);
  double lp = 0.0;
  for (std::size_t i = 0; i < d; ++i) {
    // z = (a - m) / s;  log N = -z^2/2 - log_std - log(2 pi)/2
    const double inv_s = dm::exp(-log_std[i]);
    const double z = (a[i] - mean[i]) * inv_s;
    lp += -0.5 * z * z - log_std[i] - kHalfLog2Pi;
    // d/dm = z / s;  d/dlog_std = z^2 - 1
    if (!d_mean.empty()) d_mean[i] = z * inv_s;
    if (!d_log_std.empty()) d_log_std[i] = z * z - 1.0;
  }
  return lp;
}

double diag_gaussian_entropy(std::span<const double> log_std, std::span<double> d_log_std) {
  check_optional("diag_gaussian_entropy", log_std.size(), d_log_std);
  // H = sum (1/2 + log(2 pi)/2 + log_std)
  double h = 0.0;
  for (std::size_t i = 0; i < log_std.size(); ++i) {
    h += 0.5 + kHalfLog2Pi + log_std[i];
    if (!d_log_std.empty()) d_log_std[i] = 1.0;
  }
  return h;
}

void diag_gaussian_sample(std::span<const double> mean, std::span<const double> log_std, Rng& rng,
                          std::span<double> a) {
  check_sizes("diag_gaussian_sample", mean.size(), {log_std.size(), a.size()});
  // a = m + s e
  for (std::size_t i = 0; i < mean.size(); ++i) a[i] = mean[i] + dm::exp(log_std[i]) * rng.normal();
}

SquashedGaussian squashed_gaussian(std::span<const double> mean, std::span<const double> log_std,
                                   std::span<const double> eps) {
  const std::size_t d = mean.size();
  check_sizes("squashed_gaussian", d, {log_std.size(), eps.size()});
  SquashedGaussian r;
  r.eps.assign(eps.begin(), eps.end());
  r.u.resize(d);
  r.a.resize(d);
  r.da_dmean.resize(d);
  r.da_dlog_std.resize(d);
  r.dlogp_dmean.resize(d);
  r.dlogp_dlog_std.resize(d);
  for (std::size_t i = 0; i < d; ++i) {
    // ls = clamp(log_std, -20, 2); k = 1 inside the closed interval
    const double raw = log_std[i];
    const double ls = raw < kSacLogStdMin ? kSacLogStdMin : (raw > kSacLogStdMax ? kSacLogStdMax : raw);
    const double k = (raw >= kSacLogStdMin && raw <= kSacLogStdMax) ? 1.0 : 0.0;
    const double s = dm::exp(ls);
    // u = m + s e, a = tanh(u)
    const double se = s * eps[i];
    r.u[i] = mean[i] + se;
    const double a = dm::tanh(r.u[i]);
    r.a[i] = a;
    // log pi term: log N(u; m, s) - log(1 - a^2 + 1e-6)
    const double one_m_a2 = 1.0 - a * a;
    const double q = one_m_a2 + kSquashEpsilon;
    r.log_prob += -0.5 * eps[i] * eps[i] - ls - kHalfLog2Pi - dm::log(q);
    // da/dm = 1 - a^2, da/dls = (1 - a^2) s e k
    r.da_dmean[i] = one_m_a2;
    r.da_dlog_std[i] = one_m_a2 * se * k;
    // dlogpi/du = 2 a (1 - a^2) / (1 - a^2 + 1e-6); dlogpi/dm = dlogpi/du; dlogpi/dls = (-1 + dlogpi/du s e) k
    const double dlp_du = 2.0 * a * one_m_a2 / q;
    r.dlogp_dmean[i] = dlp_du;
    r.dlogp_dlog_std[i] = (-1.0 + dlp_du * se) * k;
  }
  return r;
}

SquashedGaussian squashed_gaussian_sample(std::span<const double> mean, std::span<const double> log_std, Rng& rng) {
  std::vector<double> e(mean.size());
  for (double& x : e) x = rng.normal();
  return squashed_gaussian(mean, log_std, e);
}

void squashed_gaussian_backward(const SquashedGaussian& s, std::span<const double> d_a, double d_log_prob,
                                std::span<double> d_mean, std::span<double> d_log_std) {
  const std::size_t d = s.a.size();
  check_sizes("squashed_gaussian_backward", d, {d_a.size()});
  check_optional("squashed_gaussian_backward", d, d_mean);
  check_optional("squashed_gaussian_backward", d, d_log_std);
  // dL/dm = dL/da da/dm + dL/dlogpi dlogpi/dm (and the same for log_std)
  for (std::size_t i = 0; i < d; ++i) {
    if (!d_mean.empty()) d_mean[i] = d_a[i] * s.da_dmean[i] + d_log_prob * s.dlogp_dmean[i];
    if (!d_log_std.empty()) d_log_std[i] = d_a[i] * s.da_dlog_std[i] + d_log_prob * s.dlogp_dlog_std[i];
  }
}

}  // namespace dsb
