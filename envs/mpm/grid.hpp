#pragma once
// The background grid of the MPM engine and the particle binning that makes its work sparse and
// its scatter deterministic.
//
// Layout: nodes in a dense row-major array (z fastest), index (i n_y + j) n_z + k; the grid is
// cut into blocks of 4 x 4 x 4 nodes. Only *active* blocks are cleared, updated and read: the
// blocks a particle's 3 x 3 x 3 stencil can touch (its home block, the block of its base node, and
// the next block along each axis). Memory is dense (64^3 nodes x 7 doubles = 15 MB); work is
// proportional to the active blocks.
//
// Deterministic scatter (so that no sum depends on the threads): particles are binned by their
// home *unit*, the cube of U = 2^kUnitLog2 nodes per axis containing their base node, in a stable counting sort
// (ascending particle index inside a unit), and units are coloured by the parity of their unit
// coordinates. A particle writes nodes base..base+2, i.e. nodes uU .. uU + U + 1 along each axis,
// so two units of one colour (2U nodes apart along some axis, U >= 2) never write the same node:
// the 8 colours run one after another, the units of a colour on any threads, each unit's
// particles in ascending order. Every node therefore sums its contributions in one fixed order
// (colour, unit, particle), whatever the number of threads. Each thread takes one contiguous part
// of a colour's units holding about equal numbers of particles (`particle_balanced_part`); the
// same part of space from colour to colour and phase to phase, so the nodes stay in its core's
// cache (with dynamically shared tasks 2 threads ran P2G only 1.3x faster). U = 4 (the blocks):
// U = 2 gave 8 times as many units per colour but a 30% slower P2G on one thread (measured).
#include <array>
#include <cstdint>
#include <vector>

#include "common/thread_team.hpp"
#include "envs/mpm/mpm_types.hpp"

namespace dsb::mpm {

constexpr int kBlockLog2 = 2;
constexpr int kBlock = 1 << kBlockLog2;  // nodes per block and axis
constexpr int kUnitLog2 = 2;             // scatter units: 4 nodes per axis (the blocks)
constexpr int kColours = 8;

struct GridLayout {
  std::array<int, 3> n{};   // nodes per axis (the domain's plus `pad` below it)
  int pad = 0;              // node i is at position (i - pad) dx
  std::array<int, 3> nb{};  // blocks per axis
  std::array<int, 3> nu{};  // scatter units per axis

  GridLayout(const std::array<int, 3>& domain_nodes, int pad);
  GridLayout() = default;
  int nodes() const { return n[0] * n[1] * n[2]; }
  int blocks() const { return nb[0] * nb[1] * nb[2]; }
  int node(int i, int j, int k) const { return (i * n[1] + j) * n[2] + k; }
  int block(int bi, int bj, int bk) const { return (bi * nb[1] + bj) * nb[2] + bk; }
  std::array<int, 3> block_coords(int b) const { return {b / (nb[1] * nb[2]), (b / nb[2]) % nb[1], b % nb[2]}; }
  int units() const { return nu[0] * nu[1] * nu[2]; }
  int unit(int ui, int uj, int uk) const { return (ui * nu[1] + uj) * nu[2] + uk; }
  std::array<int, 3> unit_coords(int u) const { return {u / (nu[1] * nu[2]), (u / nu[2]) % nu[1], u % nu[2]}; }
  int unit_colour(int u) const {
    const auto c = unit_coords(u);
    return (c[0] & 1) << 2 | (c[1] & 1) << 1 | (c[2] & 1);
  }
  // node index range of block b along one axis: [lo, hi)
  void block_range(int b, std::array<int, 3>& lo, std::array<int, 3>& hi) const;
};

// fn(i, j, k, n) for every node (i, j, k) of block b, n its index, in index order
template <class Fn>
void for_each_node_of_block(const GridLayout& layout, int b, Fn&& fn) {
  std::array<int, 3> lo, hi;
  layout.block_range(b, lo, hi);
  for (int i = lo[0]; i < hi[0]; ++i)
    for (int j = lo[1]; j < hi[1]; ++j) {
      const int row = layout.node(i, j, 0);
      for (int k = lo[2]; k < hi[2]; ++k) fn(i, j, k, row + k);
    }
}

// Grid fields, dense over all nodes; only active blocks hold meaningful values.
struct GridFields {
  std::vector<Vec4> mq;  // node momentum and mass (q, m) from P2G
  std::vector<Vec3> v;   // node velocity after the grid update (read by G2P)
  void resize(int nodes);
};

// dL/dv of the node velocities after the grid update. (The reverse pass writes (dL/dq, dL/dm)
// over the restored mq of GridFields, once the grid update's adjoint has read them.)
struct GridAdjoint {
  std::vector<Vec3> v;
  void resize(int nodes);
};

// Particles binned by home unit, and the active blocks, for one substep.
struct ParticleBins {
  std::vector<int> home;                             // per particle: home unit
  std::vector<int> order;                            // particle indices sorted by home unit, stable
  std::vector<int> unit_begin;                       // per unit: first position in `order` (size units + 1)
  std::array<std::vector<int>, kColours> by_colour;  // occupied units of each colour, ascending
  std::vector<int> active;                           // active blocks, ascending
  std::vector<std::uint8_t> flag;                    // per block scratch

  // bins particles with home blocks `home` (already filled, size particles)
  void rebuild(const GridLayout& layout);
};

// The units of `units` (one colour's, in order) that part `part` of `parts` takes when the parts
// are contiguous and hold about equal numbers of particles: [first, last) into `units`.
void particle_balanced_part(const ParticleBins& bins, const std::vector<int>& units, int part, int parts,
                            std::int64_t& first, std::int64_t& last);

// fn(p) for every particle, colour by colour; within a colour each thread takes its particle-
// balanced part of the units, each unit's particles in ascending order. The one loop of every
// scatter into the grid (P2G, G2P^T): fn may add to the nodes of p's stencil without atomics.
// The lanes path's form (the same order) calls fn(p, t) with the thread t, done(t) after thread
// t's part of each colour (it finishes a chunk there), and ahead(q) with the particle kAhead
// places later in the thread's order while fn(p) runs (it prefetches q's data: the order jumps
// through memory).
constexpr int kAhead = 8;
template <class Fn, class Done, class Ahead>
void for_each_particle_by_colour(const ParticleBins& bins, ThreadTeam& team, Fn&& fn, Done&& done, Ahead&& ahead) {
  for (int c = 0; c < kColours; ++c) {
    const std::vector<int>& units = bins.by_colour[c];
    team.run_per_thread([&](int t) {
      std::int64_t first, last;
      particle_balanced_part(bins, units, t, team.size(), first, last);
      if (first < last) {
        // the thread's particles are order[o] for o in [unit_begin[units[first]], end) minus the
        // units of other colours in between: look ahead within its units only
        std::int64_t uu_ahead = first;
        int o_ahead = bins.unit_begin[units[first]];
        auto advance_ahead = [&] {
          while (uu_ahead < last && o_ahead >= bins.unit_begin[units[uu_ahead] + 1]) {
            if (++uu_ahead < last) o_ahead = bins.unit_begin[units[uu_ahead]];
          }
        };
        for (int k = 0; k < kAhead; ++k) {
          advance_ahead();
          if (uu_ahead < last) ++o_ahead;
        }
        for (std::int64_t uu = first; uu < last; ++uu)
          for (int o = bins.unit_begin[units[uu]]; o < bins.unit_begin[units[uu] + 1]; ++o) {
            advance_ahead();
            if (uu_ahead < last) ahead(bins.order[o_ahead++]);
            fn(bins.order[o], t);
          }
      }
      done(t);
    });
  }
}
template <class Fn>
void for_each_particle_by_colour(const ParticleBins& bins, ThreadTeam& team, Fn&& fn) {
  for (int c = 0; c < kColours; ++c) {
    const std::vector<int>& units = bins.by_colour[c];
    team.run_per_thread([&](int t) {
      std::int64_t first, last;
      particle_balanced_part(bins, units, t, team.size(), first, last);
      for (std::int64_t uu = first; uu < last; ++uu)
        for (int o = bins.unit_begin[units[uu]]; o < bins.unit_begin[units[uu] + 1]; ++o) fn(bins.order[o]);
    });
  }
}

// Zeroes mq (GridFields) or v (GridAdjoint) on the nodes of the given blocks.
// Each thread clears the contiguous part of `blocks` it updates later (parallel_for_per_thread), so
// the nodes stay in its core's cache.
void clear_blocks(const GridLayout& layout, const std::vector<int>& blocks, GridFields& g, ThreadTeam& team);
void clear_blocks(const GridLayout& layout, const std::vector<int>& blocks, GridAdjoint& g, ThreadTeam& team);

// A compact copy of the active blocks' fields (what the reverse pass of a substep needs).
// Block i of `active` keeps its nodes at slots 64 i + local index (edge blocks leave some unused),
// so that threads copy their parts of the block list independently.
struct GridSnapshot {
  std::vector<int> active;
  std::vector<Vec4> mq;
  std::vector<Vec3> v;
  void save(const GridLayout& layout, const std::vector<int>& blocks, const GridFields& g, ThreadTeam& team);
  void restore(const GridLayout& layout, GridFields& g, ThreadTeam& team) const;
};

}  // namespace dsb::mpm
