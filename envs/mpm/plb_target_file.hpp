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

struct PlbTargetFile {
  NodeGrid grid;          // on the scene's nodes (pad included), as build_plb_model uses a target
  std::string hash;       // FNV-1a 64 (hex) of the file's values as little-endian doubles in C order
  std::string dtype;      // "<f8" or "<f4", as the file has it (not part of the identity)
};

// Reads `path` for a scene of config `mpm`: the shape must be mpm.grid (PlasticineLab's
// (64, 64, 64)) and every value finite. Throws UsageError "PATH: problem" (npy_array.hpp's
// refusals, a wrong shape, a value that is not finite).
PlbTargetFile read_plb_target(const std::string& path, const MpmConfig& mpm);

// The other way: the values of a grid on the scene's nodes at PlasticineLab's nodes (shape
// mpm.grid, C order), dropping the pad nodes. UsageError when g is not on the scene's nodes.
std::vector<double> plb_node_values(const NodeGrid& g, const MpmConfig& mpm);

}  // namespace dsb::mpm
