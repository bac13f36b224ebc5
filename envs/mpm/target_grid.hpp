#pragma once
// Target mass grids of the PlasticineLab tasks: the node grid type, the exact distance field of a
// target (the weights of the SDF loss), the soft IoU, and the compressed files under data/targets/.
//
// PlasticineLab compares the plasticine's grid mass m (quadratic B-spline P2G of the particle
// masses onto the 64^3 nodes, node (i, j, k) at (i, j, k) dx) with a target mass grid t:
//   density loss  sum_I |m_I - t_I|,
//   SDF loss      sum_I d_I m_I, d_I the distance from node I to the nearest node with t > 1e-4,
//   soft IoU      S / (sum m / max m + sum t / max t - S),  S = sum m t / (max m max t).
// PlasticineLab approximates d by propagation (each node takes the minimum over the offsets in
// [-3, 2]^3 of the neighbour's distance plus the offset's length, repeated 128 times);
// distance_to_mass() computes the exact Euclidean distance instead.
//
// Files (write_grid_gz / read_grid_gz): gzip of a text format,
//   dsb-node-grid 1 n0 n1 n2 count            header: format name, version, shape, entries
//   i j k value                               `count` lines, value as printf %.17g (round-trips)
// one line per node whose value is not +0.0 (a -0.0 is written, so every bit survives), in index
// order. Written with compression level 9 and a gzip header without name and with mtime 0, so one
// zlib writes the same bytes every time. Different zlib versions may compress differently:
// compare targets by their decoded values, never by their compressed bytes.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace dsb::mpm {

// Values on the nodes of an n[0] x n[1] x n[2] grid, row-major with z fastest: node (i, j, k) at
// index (i n[1] + j) n[2] + k. An aggregate: NodeGrid{{n0, n1, n2}, values}.
struct NodeGrid {
  std::array<int, 3> n{};
  std::vector<double> values;

  static NodeGrid zeros(const std::array<int, 3>& n);  // every value 0
  std::size_t size() const;                            // n0 n1 n2 (the expected values.size())
  std::size_t index(int i, int j, int k) const { return (static_cast<std::size_t>(i) * n[1] + j) * n[2] + k; }
  double& at(int i, int j, int k) { return values[index(i, j, k)]; }
  double at(int i, int j, int k) const { return values[index(i, j, k)]; }
  double sum() const;  // in index order
  double max() const;  // largest value; -infinity for a grid without nodes
};

// The exact Euclidean distance, in world units (node spacing dx), from every node to the nearest
// node whose value is > threshold (0 at those nodes); empty_value at every node when no value
// exceeds the threshold. Squared distances are computed exactly in integers (node units) by the
// separable lower-envelope-of-parabolas transform of Felzenszwalb & Huttenlocher (2012), one pass
// per axis, O(nodes); the result at a node is sqrt(integer) * dx: deterministic, and equal to the
// brute-force minimum over the target nodes. Throws std::invalid_argument when values.size() !=
// size() or an axis exceeds 65536 nodes. Indexed like target.values.
std::vector<double> distance_to_mass(const NodeGrid& target, double threshold, double dx, double empty_value = 1000.0);

// PlasticineLab's soft IoU of two grids of one shape (formula above), sums in index order.
// 0 when either grid has no positive value (in particular when it is all zero), where the formula
// would divide by max = 0. For non-negative grids the denominator is >= 1 and the result lies in
// [0, 1]; it is 1 for identical grids only when every value is 0 or the max. Small negative
// values (PlasticineLab targets have some) enter the formula as they are; a denominator <= 0
// (possible only with negative values) gives 0. Throws std::invalid_argument on different shapes.
double soft_iou(const NodeGrid& mass, const NodeGrid& target);

// Writes g as a gzip-compressed dsb-node-grid file (format above). Throws dsb::UsageError naming
// the file when a value is not finite or the file cannot be written; std::invalid_argument when
// values.size() != size().
void write_grid_gz(const std::string& path, const NodeGrid& g);

// Reads a file written by write_grid_gz. Checks the gzip stream (complete, CRC, nothing after it),
// the header, the entry count, index ranges, duplicate nodes and number syntax (finite doubles as
// from_chars reads them); throws dsb::UsageError with a one-line message naming the file and the
// problem. Shapes are limited to 65536 nodes per axis and 2^24 nodes in all.
NodeGrid read_grid_gz(const std::string& path);

}  // namespace dsb::mpm
