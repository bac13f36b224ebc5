#include "envs/mpm/plb_target_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string_view>

#include "common/error.hpp"
#include "common/number_text.hpp"
#include "common/rng.hpp"
#include "common/shown_value.hpp"
#include "envs/mpm/npy_array.hpp"

namespace dsb::mpm {

namespace {

std::string hex64(std::uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace

PlbTargetFile read_plb_target(const std::string& path, const MpmConfig& mpm) {
  const NpyArray a = read_npy(path);
  const std::vector<std::size_t> want(mpm.grid.begin(), mpm.grid.end());
  if (a.shape != want)
    throw UsageError(shown_value(path) + ": shape " + npy_shape_text(a.shape) + " is not a target grid's " +
                     npy_shape_text(want) + " (PlasticineLab's nodes)");
  // "value V at [i, j, k]": the first cell in C order that is not a target's mass
  const auto refuse_cell = [&](std::size_t n, const std::string& why) {
    const std::size_t k = n % want[2], j = n / want[2] % want[1], i = n / want[2] / want[1];
    throw UsageError(shown_value(path) + ": value " + number_text(a.values[n]) + " at [" + std::to_string(i) + ", " +
                     std::to_string(j) + ", " + std::to_string(k) + "] " + why);
  };
  double largest = -std::numeric_limits<double>::infinity();
  for (std::size_t n = 0; n < a.values.size(); ++n) {
    const double v = a.values[n];
    if (!std::isfinite(v)) refuse_cell(n, "is not finite");
    if (v < -kTargetNegativeTolerance)
      refuse_cell(n,
                  "is negative: a target is a grid of masses (values from " + number_text(-kTargetNegativeTolerance) +
                      " are taken as rounding, as in PlasticineLab's own files)");
    if (v > kMaxTargetMass)
      refuse_cell(n, "is above " + number_text(kMaxTargetMass) + ", where the loss could overflow to inf or nan");
    largest = std::max(largest, v);
  }
  if (!(largest > 0.0))
    throw UsageError(shown_value(path) + ": no positive mass (the largest value is " + number_text(largest) +
                     "): a target is a grid of masses with some mass in it");
  PlbTargetFile t;
  t.dtype = a.dtype;
  t.hash = hex64(
      fnv1a64(std::string_view(reinterpret_cast<const char*>(a.values.data()), a.values.size() * sizeof(double))));
  const int p = mpm.pad;
  t.grid = NodeGrid::zeros({mpm.grid[0] + p, mpm.grid[1] + p, mpm.grid[2] + p});
  std::size_t n = 0;
  for (int i = 0; i < mpm.grid[0]; ++i)
    for (int j = 0; j < mpm.grid[1]; ++j)
      for (int k = 0; k < mpm.grid[2]; ++k) t.grid.at(i + p, j + p, k + p) = a.values[n++];
  return t;
}

std::vector<double> plb_node_values(const NodeGrid& g, const MpmConfig& mpm) {
  const int p = mpm.pad;
  if (g.n != std::array<int, 3>{mpm.grid[0] + p, mpm.grid[1] + p, mpm.grid[2] + p} || g.values.size() != g.size())
    throw UsageError("a grid of " + std::to_string(g.n[0]) + " x " + std::to_string(g.n[1]) + " x " +
                     std::to_string(g.n[2]) + " nodes is not on the scene's nodes");
  std::vector<double> v;
  v.reserve(static_cast<std::size_t>(mpm.grid[0]) * mpm.grid[1] * mpm.grid[2]);
  for (int i = 0; i < mpm.grid[0]; ++i)
    for (int j = 0; j < mpm.grid[1]; ++j)
      for (int k = 0; k < mpm.grid[2]; ++k) v.push_back(g.at(i + p, j + p, k + p));
  return v;
}

}  // namespace dsb::mpm
