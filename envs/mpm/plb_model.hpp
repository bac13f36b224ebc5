#pragma once
// A PlasticineLab task's model: the MPM model (plasticine sampled from the task's shapes with our
// seeded RNG, PlasticineLab's material and constants, the manipulators) and the target with its
// distance field, built once per env.
#include <string>
#include <vector>

#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/plb_config.hpp"
#include "envs/mpm/target_grid.hpp"

namespace dsb::mpm {

struct PlbModel {
  MpmModel mpm;
  NodeGrid target;                            // target grid mass on the engine's nodes (pad included)
  std::vector<double> target_sdf;             // per node: distance to the nearest node above the threshold
  double target_sum = 0.0, target_max = 0.0;  // sum_I t_I (the soft IoU's), max_I t_I
  double target_abs_sum = 0.0;                // sum_I |t_I|: the density term where m = 0
  std::vector<int> movable;                   // primitives with commands (the contact term's)
};

// The MPM model alone, without the target (what the reference motion runs on).
MpmModel build_plb_mpm_model(const PlbConfig& cfg);
// The MPM model and the target: cfg.target_file's when it has one, else read from plb_target_path(cfg.task).
PlbModel build_plb_model(const PlbConfig& cfg);

std::string plb_target_path(const std::string& task);  // <data dir>/targets/plb-<task>.txt.gz

}  // namespace dsb::mpm
