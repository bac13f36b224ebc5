#pragma once
// Shared by the cloth env tests: whether a difference window of half-width h around x crosses a
// contact switch, judged by an env's per-step contact pattern (Env::contact_pattern of swing and
// flip): smooth at scale h when the pattern is the same at x +- h along every coordinate.
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

}  // namespace dsb::testing
