#include "envs/mpm/plb_target_file.hpp"

#include <cmath>
#include <cstdio>
#include <string_view>

#include "common/error.hpp"
#include "common/rng.hpp"
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
    throw UsageError(path + ": shape " + npy_shape_text(a.shape) + " is not a target grid's " + npy_shape_text(want) +
                     " (PlasticineLab's nodes)");
  for (std::size_t n = 0; n < a.values.size(); ++n)
    if (!std::isfinite(a.values[n])) {
      const std::size_t k = n % want[2], j = n / want[2] % want[1], i = n / want[2] / want[1];
      throw UsageError(path + ": value " + std::to_string(a.values[n]) + " at [" + std::to_string(i) + ", " +
                       std::to_string(j) + ", " + std::to_string(k) + "] is not finite");
    }
  PlbTargetFile t;
  t.dtype = a.dtype;
  t.hash = hex64(fnv1a64(std::string_view(reinterpret_cast<const char*>(a.values.data()),
                                          a.values.size() * sizeof(double))));
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
