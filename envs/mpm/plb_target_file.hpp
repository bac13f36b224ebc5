#pragma once
// A PlasticineLab-format target grid read from a `.npy` file (the `target` option of `plb-NAME`,
// `--set plb-NAME.target=PATH`), in place of our generated data/targets/plb-NAME.txt.gz.
//
// PlasticineLab saves a task's target as the grid mass on its 64^3 nodes: an .npy array of shape
// (64, 64, 64) (npy_array.hpp), entry [i, j, k] the mass at node (i, j, k) dx, dx = 1/64. Our
// scene's node grid has `pad` extra nodes below 0 on every axis (node I at (I - pad) dx), so entry
// [i, j, k] goes to our node (i + pad, j + pad, k + pad) and the pad nodes hold 0 (PlasticineLab's
// grid has no node there). float32 files are read as the doubles of their values.
//
// The target's identity is the hash of its values, not its path: the same grid from any file, in
// float64 or in a float32 of the same values, is the same target, and any other grid another.
#include <cstddef>
#include <string>
#include <vector>

#include "envs/mpm/mpm_config.hpp"
#include "envs/mpm/target_grid.hpp"

namespace dsb::mpm {

// A target is a grid of masses, so read_plb_target refuses what none is:
//
// kTargetNegativeTolerance: the most negative value taken is -1e-4. A grid of masses (P2G of
// particle masses with non-negative B-spline weights) is >= 0 everywhere, but PlasticineLab's own
// target files hold tiny negatives (Rope, TripleMove, Writer; down to -2.3e-5 in TripleMove; how
// they were made is not documented), and those must load. 1e-4 is 4.3x the deepest of them, and
// it is the SDF loss's threshold (PlbConfig::target_threshold): a node at or below it is empty to
// that term, so a value in [-1e-4, 0) is as empty to the loss as 0 and moves the density term by
// at most 1e-4 (plb_loss.hpp sums |m_I - t_I| as it is). A cell at -5, or a grid of -1 (once
// taken, a loss of -12 million, below any real solution's), is refused.
inline constexpr double kTargetNegativeTolerance = 1e-4;
// kMaxTargetMass: the largest value taken is 1e299. The loss (plb_loss.hpp) sums over at most 50 env
// steps density_weight (10) x sum_I |m_I - t_I| over the 64^3 = 262,144 nodes, besides terms of the
// plasticine alone; with every t_I at the bound that is at most 50 x 10 x 262,144 x 1e299 = 1.3e307
// plus the plasticine's mass, 13x below the largest double (1.8e308); the soft IoU's sum_I m_I t_I
// is the plasticine's mass (0.61) times at most the same. A cell at 1.7e308 made loss and gradient
// nan. PlbConfig::validate checks that its steps, weight and grid keep within this bound.
inline constexpr double kMaxTargetMass = 1e299;
// ... and a grid with no value above 0 (no mass at all) is refused too.

struct PlbTargetFile {
  NodeGrid grid;      // on the scene's nodes (pad included), as build_plb_model uses a target
  std::string hash;   // FNV-1a 64 (hex) of the file's values as little-endian doubles in C order
  std::string dtype;  // "<f8" or "<f4", as the file has it (not part of the identity)
};

// Reads `path` for a scene of config `mpm`: the shape must be mpm.grid (PlasticineLab's
// (64, 64, 64)), every value finite and in [-kTargetNegativeTolerance, kMaxTargetMass], and one
// above 0. Throws UsageError "PATH: problem", one line (npy_array.hpp's refusals, a wrong shape; a
// value out of range with its cell [i, j, k], the first in C order; no positive value).
PlbTargetFile read_plb_target(const std::string& path, const MpmConfig& mpm);

// The other way: the values of a grid on the scene's nodes at PlasticineLab's nodes (shape
// mpm.grid, C order), dropping the pad nodes. UsageError when g is not on the scene's nodes.
std::vector<double> plb_node_values(const NodeGrid& g, const MpmConfig& mpm);

}  // namespace dsb::mpm
