#pragma once
// Shared by the cloth env tests: whether a difference window of half-width h around x crosses a
// contact switch, judged by an env's per-step contact pattern (Env::contact_pattern of swing and
// flip): smooth at scale h when the pattern is the same at x +- h along every coordinate; and the
// bisection to a contact switch along one coordinate that both use to show what the loss and the
// gradient do there.
#include <cmath>
#include <vector>

namespace dsb::testing {

template <class ContactEnv>
bool smooth_at(const ContactEnv& env, const std::vector<double>& x, double h) {
  const auto pattern = env.contact_pattern(x);
  for (int i = 0; i < env.dim(); ++i)
    for (double s : {-h, h}) {
      auto y = x;
      y[i] += s;
      if (env.contact_pattern(y) != pattern) return false;
    }
  return true;
}

// What the loss and the gradient do across a contact switch along coordinate i: bisected from x
// towards x + width until the pattern changes within 1e-13 (a keeps x's pattern, b does not).
struct ContactSwitch {
  bool found = false;              // the pattern changes within width, and x - h stays on a's piece
  double at = 0.0, bracket = 0.0;  // a[i] and b[i] - a[i]
  double jump = 0.0;               // loss(b) - loss(a)
  double left_difference = 0.0;    // (loss(a) - loss(a - h e_i)) / h, inside a's piece
  double analytic = 0.0;           // dLoss/dx_i at a (loss_and_grad)
  bool gradient_finite = false;
};

template <class ContactEnv>
ContactSwitch across_contact_switch(const ContactEnv& env, std::vector<double> a, int i, double width, double h) {
  ContactSwitch r;
  auto b = a;
  b[i] += width;
  const auto pa = env.contact_pattern(a);
  if (env.contact_pattern(b) == pa) return r;
  while (b[i] - a[i] > 1e-13) {
    auto mid = a;
    mid[i] = 0.5 * (a[i] + b[i]);
    (env.contact_pattern(mid) == pa ? a : b) = mid;
  }
  std::vector<double> grad(a.size());
  const double loss = env.loss_and_grad(a, grad);
  r.gradient_finite = true;
  for (double g : grad) r.gradient_finite = r.gradient_finite && std::isfinite(g);
  auto left = a;
  left[i] -= h;
  r.found = env.contact_pattern(left) == pa;
  r.at = a[i];
  r.bracket = b[i] - a[i];
  r.jump = env.loss(b) - loss;
  r.left_difference = (loss - env.loss(left)) / h;
  r.analytic = grad[i];
  return r;
}

}  // namespace dsb::testing
