#include "envs/mpm/grid.hpp"

#include <algorithm>

#include "common/parallel.hpp"

namespace dsb::mpm {

GridLayout::GridLayout(const std::array<int, 3>& domain_nodes, int pad_nodes) : pad(pad_nodes) {
  for (int a = 0; a < 3; ++a) {
    n[a] = domain_nodes[a] + pad;
    nb[a] = (n[a] + kBlock - 1) / kBlock;
    nu[a] = (n[a] + (1 << kUnitLog2) - 1) >> kUnitLog2;
  }
}

void GridLayout::block_range(int b, std::array<int, 3>& lo, std::array<int, 3>& hi) const {
  const auto c = block_coords(b);
  for (int a = 0; a < 3; ++a) {
    lo[a] = c[a] * kBlock;
    hi[a] = std::min(n[a], lo[a] + kBlock);
  }
}

void GridFields::resize(int nodes) {
  mq.assign(nodes, Vec4::Zero());
  v.assign(nodes, Vec3::Zero());
}

void GridAdjoint::resize(int nodes) { v.assign(nodes, Vec3::Zero()); }

void ParticleBins::rebuild(const GridLayout& layout) {
  const int units = layout.units();
  const int particles = static_cast<int>(home.size());
  unit_begin.assign(units + 1, 0);
  for (int p = 0; p < particles; ++p) ++unit_begin[home[p] + 1];
  for (int u = 0; u < units; ++u) unit_begin[u + 1] += unit_begin[u];
  order.resize(particles);
  // stable counting sort: a cursor per unit starting at unit_begin
  std::vector<int>& cursor = active;  // reused as scratch, rebuilt below
  cursor.assign(unit_begin.begin(), unit_begin.end() - 1);
  for (int p = 0; p < particles; ++p) order[cursor[home[p]]++] = p;

  for (auto& c : by_colour) c.clear();
  flag.assign(layout.blocks(), 0);
  for (int u = 0; u < units; ++u) {
    if (unit_begin[u + 1] == unit_begin[u]) continue;
    by_colour[layout.unit_colour(u)].push_back(u);
    // the unit's particles write nodes from its first node to 2 past its last, along each axis:
    // the blocks holding them
    const auto c = layout.unit_coords(u);
    std::array<int, 3> lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = (c[a] << kUnitLog2) >> kBlockLog2;
      hi[a] = std::min(layout.nb[a] - 1, ((c[a] << kUnitLog2) + (1 << kUnitLog2) + 1) >> kBlockLog2);
    }
    for (int bi = lo[0]; bi <= hi[0]; ++bi)
      for (int bj = lo[1]; bj <= hi[1]; ++bj)
        for (int bk = lo[2]; bk <= hi[2]; ++bk) flag[layout.block(bi, bj, bk)] = 1;
  }
  active.clear();
  for (int b = 0; b < layout.blocks(); ++b)
    if (flag[b]) active.push_back(b);
}

void particle_balanced_part(const ParticleBins& bins, const std::vector<int>& units, int part, int parts,
                            std::int64_t& first, std::int64_t& last) {
  std::int64_t total = 0;
  for (int u : units) total += bins.unit_begin[u + 1] - bins.unit_begin[u];
  // part t starts at the first unit whose preceding particles reach t total / parts
  auto start_of = [&](int t) {
    const std::int64_t target = total * t / parts;
    std::int64_t seen = 0, i = 0;
    const auto n = static_cast<std::int64_t>(units.size());
    while (i < n && seen < target) {
      seen += bins.unit_begin[units[i] + 1] - bins.unit_begin[units[i]];
      ++i;
    }
    return t == 0 ? std::int64_t{0} : (t == parts ? n : i);
  };
  first = start_of(part);
  last = start_of(part + 1);
}

namespace {

template <class Fn>
void for_nodes_of_blocks_in_parallel(const GridLayout& layout, const std::vector<int>& blocks, ThreadTeam& team,
                                     Fn&& fn) {
  parallel_for_per_thread(team, static_cast<std::int64_t>(blocks.size()), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i)
      for_each_node_of_block(layout, blocks[i], [&](int, int, int, int n) { fn(n); });
  });
}

}  // namespace

void clear_blocks(const GridLayout& layout, const std::vector<int>& blocks, GridFields& g, ThreadTeam& team) {
  for_nodes_of_blocks_in_parallel(layout, blocks, team, [&](int n) { g.mq[n].setZero(); });
}

void clear_blocks(const GridLayout& layout, const std::vector<int>& blocks, GridAdjoint& g, ThreadTeam& team) {
  for_nodes_of_blocks_in_parallel(layout, blocks, team, [&](int n) { g.v[n].setZero(); });
}

namespace {

constexpr int kBlockNodes = kBlock * kBlock * kBlock;

// fn(node, slot) for the nodes of blocks[i], slot = kBlockNodes i + local index, in parallel parts
template <class Fn>
void for_block_slots(const GridLayout& layout, const std::vector<int>& blocks, ThreadTeam& team, Fn&& fn) {
  parallel_for_per_thread(team, static_cast<std::int64_t>(blocks.size()), [&](std::int64_t begin, std::int64_t end) {
    std::array<int, 3> lo, hi;
    for (std::int64_t b = begin; b < end; ++b) {
      layout.block_range(blocks[b], lo, hi);
      for_each_node_of_block(layout, blocks[b], [&](int i, int j, int k, int n) {
        fn(n, kBlockNodes * b + ((i - lo[0]) * kBlock + (j - lo[1])) * kBlock + (k - lo[2]));
      });
    }
  });
}

}  // namespace

void GridSnapshot::save(const GridLayout& layout, const std::vector<int>& blocks, const GridFields& g,
                        ThreadTeam& team) {
  active = blocks;
  mq.resize(blocks.size() * kBlockNodes);
  v.resize(blocks.size() * kBlockNodes);
  for_block_slots(layout, active, team, [&](int n, std::int64_t slot) {
    mq[slot] = g.mq[n];
    v[slot] = g.v[n];
  });
}

void GridSnapshot::restore(const GridLayout& layout, GridFields& g, ThreadTeam& team) const {
  for_block_slots(layout, active, team, [&](int n, std::int64_t slot) {
    g.mq[n] = mq[slot];
    g.v[n] = v[slot];
  });
}

}  // namespace dsb::mpm
