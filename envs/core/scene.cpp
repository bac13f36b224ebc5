#include "envs/core/scene.hpp"

#include <algorithm>

#include "common/error.hpp"

namespace dsb {

std::vector<int> frame_steps(int steps, int n) {
  if (n < 1 || steps < 0) throw ConfigError("render", "frames", "needs n >= 1 and steps >= 0");
  // round(k steps / (n - 1)) for k = 0 .. n - 1, in integers
  if (n == 1) return {steps};
  std::vector<int> out;
  for (int k = 0; k < n; ++k) out.push_back(static_cast<int>((2LL * k * steps + (n - 1)) / (2LL * (n - 1))));
  // more frames than steps: each step once
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace dsb
