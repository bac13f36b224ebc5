#pragma once
// Action distributions of the RL baselines, per sample (one action vector of dimension d):
//   - diagonal Gaussian with a state-independent log-std (SB3 PPO's DiagGaussianDistribution);
//   - tanh-squashed diagonal Gaussian (SB3 SAC's SquashedDiagGaussianDistribution), with its
//     reparameterised derivatives for the actor loss.
// Derivatives are written (not added) to the given spans; an empty span skips that derivative.
#include <span>
#include <vector>

#include "common/rng.hpp"

namespace dsb {

// ---- diagonal Gaussian (PPO) -----------------------------------------------------------------

// log N(a; mean, diag(exp(log_std))^2) = sum_i [-(a_i - m_i)^2 / (2 s_i^2) - log_std_i - log(2 pi)/2]
// d/dm_i = (a_i - m_i) / s_i^2,  d/dlog_std_i = (a_i - m_i)^2 / s_i^2 - 1.   All spans d long.
double diag_gaussian_log_prob(std::span<const double> a, std::span<const double> mean, std::span<const double> log_std,
                              std::span<double> d_mean = {}, std::span<double> d_log_std = {});

// entropy = sum_i [1/2 + log(2 pi)/2 + log_std_i];  d/dlog_std_i = 1
double diag_gaussian_entropy(std::span<const double> log_std, std::span<double> d_log_std = {});

// a = mean + exp(log_std) * e, e_i = rng.normal() for i = 0 .. d-1
void diag_gaussian_sample(std::span<const double> mean, std::span<const double> log_std, Rng& rng, std::span<double> a);

// ---- tanh-squashed Gaussian (SAC) ------------------------------------------------------------

inline constexpr double kSacLogStdMin = -20.0;  // SB3 LOG_STD_MIN
inline constexpr double kSacLogStdMax = 2.0;    // SB3 LOG_STD_MAX
inline constexpr double kSquashEpsilon = 1e-6;  // SB3 SquashedDiagGaussianDistribution.epsilon

// One reparameterised draw: ls = clamp(log_std, -20, 2), s = exp(ls), u = m + s e, a = tanh(u),
//   log pi(a) = sum_i log N(u_i; m_i, s_i) - sum_i log(1 - a_i^2 + 1e-6)
// with log N(u_i; m_i, s_i) = -e_i^2 / 2 - ls_i - log(2 pi)/2 (SB3 evaluates it from u; the same
// value up to rounding, without the cancellation in (u - m) / s when s is tiny).
// Partial derivatives at fixed e (a_i and the i-th terms depend only on m_i and log_std_i):
//   da_i/dm_i = 1 - a_i^2                      da_i/dlog_std_i = (1 - a_i^2) s_i e_i k_i
//   dlogpi/dm_i = 2 a_i (1 - a_i^2) / (1 - a_i^2 + 1e-6)
//   dlogpi/dlog_std_i = (-1 + dlogpi/dm_i * s_i e_i) k_i
// where k_i = 1 if -20 <= log_std_i <= 2, else 0 (torch.clamp passes the gradient on the closed
// interval). The Gaussian term's total derivative is 0 in m and -1 in ls: the explicit
// (u - m)/s^2 and the path through u cancel.
struct SquashedGaussian {
  std::vector<double> eps;                          // e (d), the standard normal draw
  std::vector<double> u;                            // pre-squash action (d)
  std::vector<double> a;                            // action tanh(u) in (-1, 1) (d)
  double log_prob = 0.0;                            // log pi(a)
  std::vector<double> da_dmean, da_dlog_std;        // (d)
  std::vector<double> dlogp_dmean, dlogp_dlog_std;  // (d)
};

// at a given e (tests, replay of a draw)
SquashedGaussian squashed_gaussian(std::span<const double> mean, std::span<const double> log_std,
                                   std::span<const double> eps);
// with e_i = rng.normal(), i = 0 .. d-1
SquashedGaussian squashed_gaussian_sample(std::span<const double> mean, std::span<const double> log_std, Rng& rng);

// Chain rule for a loss L(a, log pi) (SAC actor: L = alpha log pi - Q(s, a), so d_log_prob = alpha
// and d_a = -dQ/da): writes dL/dm_i = d_a_i da_i/dm_i + d_log_prob dlogpi/dm_i and likewise dL/dlog_std_i.
void squashed_gaussian_backward(const SquashedGaussian& s, std::span<const double> d_a, double d_log_prob,
                                std::span<double> d_mean, std::span<double> d_log_std);

}  // namespace dsb
