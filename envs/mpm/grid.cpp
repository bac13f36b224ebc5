#include "envs/mpm/grid.hpp"

#include <algorithm>

namespace dsb::mpm {

GridLayout::GridLayout(const std::array<int, 3>& nodes) : n(nodes) {
  for (int a = 0; a < 3; ++a) nb[a] = (n[a] + kBlock - 1) / kBlock;
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
  const int blocks = layout.blocks();
  const int particles = static_cast<int>(home.size());
  block_begin.assign(blocks + 1, 0);
  for (int p = 0; p < particles; ++p) ++block_begin[home[p] + 1];
  for (int b = 0; b < blocks; ++b) block_begin[b + 1] += block_begin[b];
  order.resize(particles);
  // stable counting sort: a cursor per block starting at block_begin
  std::vector<int>& cursor = active;  // reused as scratch, rebuilt below
  cursor.assign(block_begin.begin(), block_begin.end() - 1);
  for (int p = 0; p < particles; ++p) order[cursor[home[p]]++] = p;

  for (auto& c : by_colour) c.clear();
  flag.assign(blocks, 0);
  for (int b = 0; b < blocks; ++b) {
    if (block_begin[b + 1] == block_begin[b]) continue;
    by_colour[layout.colour(b)].push_back(b);
    // the home block and the next block along each axis
    const auto c = layout.block_coords(b);
    for (int di = 0; di < 2; ++di)
      for (int dj = 0; dj < 2; ++dj)
        for (int dk = 0; dk < 2; ++dk) {
          const int bi = c[0] + di, bj = c[1] + dj, bk = c[2] + dk;
          if (bi < layout.nb[0] && bj < layout.nb[1] && bk < layout.nb[2]) flag[layout.block(bi, bj, bk)] = 1;
        }
  }
  active.clear();
  for (int b = 0; b < blocks; ++b)
    if (flag[b]) active.push_back(b);
}

namespace {

template <class Fn>
void for_nodes_of_blocks(const GridLayout& layout, const std::vector<int>& blocks, Fn&& fn) {
  for (int b : blocks) for_each_node_of_block(layout, b, [&](int, int, int, int n) { fn(n); });
}

}  // namespace

void clear_blocks(const GridLayout& layout, const std::vector<int>& blocks, GridFields& g) {
  for_nodes_of_blocks(layout, blocks, [&](int n) { g.mq[n].setZero(); });
}

void clear_blocks(const GridLayout& layout, const std::vector<int>& blocks, GridAdjoint& g) {
  for_nodes_of_blocks(layout, blocks, [&](int n) { g.v[n].setZero(); });
}

void GridSnapshot::save(const GridLayout& layout, const std::vector<int>& blocks, const GridFields& g) {
  active = blocks;
  mq.clear();
  v.clear();
  for_nodes_of_blocks(layout, blocks, [&](int n) {
    mq.push_back(g.mq[n]);
    v.push_back(g.v[n]);
  });
}

void GridSnapshot::restore(const GridLayout& layout, GridFields& g) const {
  std::size_t i = 0;
  for_nodes_of_blocks(layout, active, [&](int n) {
    g.mq[n] = mq[i];
    g.v[n] = v[i];
    ++i;
  });
}

}  // namespace dsb::mpm
