#include "envs/mpm/mpm_model.hpp"

#include <algorithm>
#include <numeric>

#include "common/error.hpp"
#include "envs/mpm/kernel.hpp"

namespace dsb::mpm {

int MpmModel::action_dim() const {
  int d = 0;
  for (const auto& p : primitives) d += p.action_dim();
  return d;
}

int MpmModel::action_offset(int primitive) const {
  int d = 0;
  for (int i = 0; i < primitive; ++i) d += primitives[i].action_dim();
  return d;
}

void MpmModel::finalize(const std::string& owner) {
  config.validate(owner.c_str());
  layout = GridLayout(config.grid, config.pad);
  for (std::size_t m = 0; m < materials.size(); ++m)
    materials[m].validate(owner, "materials[" + std::to_string(m) + "]");
  const int n = particles();
  material_of.assign(n, -1);
  mass.assign(n, 0.0);
  volume.assign(n, 0.0);
  for (const auto& b : bodies) {
    if (b.material < 0 || b.material >= static_cast<int>(materials.size()))
      throw ConfigError(owner, "bodies." + b.name + ".material", "out of range");
    if (b.begin < 0 || b.end > n || b.begin > b.end)
      throw ConfigError(owner, "bodies." + b.name, "particle range out of bounds");
    if (!(b.particle_volume > 0.0)) throw ConfigError(owner, "bodies." + b.name + ".particle_volume", "must be > 0");
    for (int p = b.begin; p < b.end; ++p) {
      if (material_of[p] != -1) throw ConfigError(owner, "bodies." + b.name, "overlaps another body");
      material_of[p] = b.material;
      volume[p] = b.particle_volume;
      mass[p] = materials[b.material].density * b.particle_volume;
    }
  }
  for (int p = 0; p < n; ++p)
    if (material_of[p] == -1)
      throw ConfigError(owner, "bodies", "particle " + std::to_string(p) + " belongs to no body");
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < 3; ++a)
      if (!(initial[p].x[a] >= config.clamp_low() && initial[p].x[a] <= config.clamp_high(a)))
        throw ConfigError(owner, "particles", "particle " + std::to_string(p) + " starts outside the domain");
  // memory order = space order: each body's particles sorted (stably) by their starting home
  // block, so that the block-ordered sweeps of P2G read particles nearly in sequence
  const double inv_dx = 1.0 / config.dx;
  std::vector<int> order;
  std::vector<int> home(n);
  for (int p = 0; p < n; ++p) {
    const Stencil s = make_stencil(initial[p].x, inv_dx, layout);
    home[p] = layout.block(s.base[0] >> kBlockLog2, s.base[1] >> kBlockLog2, s.base[2] >> kBlockLog2);
  }
  std::vector<Particle> sorted(initial.begin(), initial.end());
  for (const auto& b : bodies) {
    order.resize(b.end - b.begin);
    std::iota(order.begin(), order.end(), b.begin);
    std::stable_sort(order.begin(), order.end(), [&](int a, int c) { return home[a] < home[c]; });
    for (int i = 0; i < b.end - b.begin; ++i) sorted[b.begin + i] = initial[order[i]];
  }
  initial = std::move(sorted);
  initial_poses.clear();
  for (std::size_t i = 0; i < primitives.size(); ++i) {
    primitives[i].validate(owner, "primitives[" + std::to_string(i) + "]");
    initial_poses.push_back(initial_pose(primitives[i]));
  }
}

}  // namespace dsb::mpm
