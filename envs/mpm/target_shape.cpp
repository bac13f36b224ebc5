#include "envs/mpm/target_shape.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dsb::mpm {

TargetShape describe_target_shape(const NodeGrid& g, int pad, double dx, double fraction) {
  if (g.values.size() != g.size()) throw std::invalid_argument("describe_target_shape: values do not fill the grid");
  if (!(fraction > 0.0 && fraction < 1.0)) throw std::invalid_argument("describe_target_shape: fraction not in (0, 1)");
  const double top = g.max();
  if (!(top > 0.0)) throw std::invalid_argument("describe_target_shape: no positive value");
  TargetShape s;
  s.threshold = fraction * top;
  auto position = [&](int i, int j, int k) { return Vec3((i - pad) * dx, (j - pad) * dx, (k - pad) * dx); };
  // mass and centre of every node
  Vec3 moment = Vec3::Zero();
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k) {
        const double v = g.at(i, j, k);
        s.mass += v;
        moment += v * position(i, j, k);
      }
  s.centre = moment / s.mass;
  // bodies: flood fill over face neighbours of the cells above the threshold, seeds in index order
  std::vector<int> body(g.size(), -1);
  std::vector<std::size_t> stack;
  s.lo = Vec3::Constant(INFINITY);
  s.hi = Vec3::Constant(-INFINITY);
  for (std::size_t seed = 0; seed < g.size(); ++seed) {
    if (!(g.values[seed] > s.threshold) || body[seed] >= 0) continue;
    TargetBody b;
    b.lo = Vec3::Constant(INFINITY);
    b.hi = Vec3::Constant(-INFINITY);
    Vec3 m = Vec3::Zero();
    const int id = static_cast<int>(s.bodies.size());
    body[seed] = id;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const std::size_t n = stack.back();
      stack.pop_back();
      const int k = static_cast<int>(n % g.n[2]), j = static_cast<int>(n / g.n[2] % g.n[1]),
                i = static_cast<int>(n / g.n[2] / g.n[1]);
      const Vec3 x = position(i, j, k);
      b.mass += g.values[n];
      m += g.values[n] * x;
      b.lo = b.lo.cwiseMin(x);
      b.hi = b.hi.cwiseMax(x);
      ++b.cells;
      const int nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
      for (const auto& c : nb) {
        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= g.n[0] || c[1] >= g.n[1] || c[2] >= g.n[2]) continue;
        const std::size_t q = g.index(c[0], c[1], c[2]);
        if (g.values[q] > s.threshold && body[q] < 0) {
          body[q] = id;
          stack.push_back(q);
        }
      }
    }
    b.centre = m / b.mass;
    s.lo = s.lo.cwiseMin(b.lo);
    s.hi = s.hi.cwiseMax(b.hi);
    s.cells += b.cells;
    s.bodies.push_back(b);
  }
  std::stable_sort(s.bodies.begin(), s.bodies.end(),
                   [](const TargetBody& a, const TargetBody& b) { return a.cells > b.cells; });
  return s;
}

double box_iou(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b, double dx) {
  // cells along an axis of [lo, hi] inclusive: round((hi - lo) / dx) + 1
  auto cells = [dx](double lo, double hi) { return std::max(0.0, std::round((hi - lo) / dx) + 1.0); };
  double both = 1.0, a = 1.0, b = 1.0;
  for (int ax = 0; ax < 3; ++ax) {
    a *= cells(lo_a[ax], hi_a[ax]);
    b *= cells(lo_b[ax], hi_b[ax]);
    both *= cells(std::max(lo_a[ax], lo_b[ax]), std::min(hi_a[ax], hi_b[ax]));
  }
  const double either = a + b - both;
  return either > 0.0 ? both / either : 0.0;
}

}  // namespace dsb::mpm
