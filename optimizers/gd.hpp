#pragma once
// Gradient descent with Adam in the normalized box, clipped to [-1, 1]:
//  - `gd` runs one descent from the box centre for the whole budget;
//  - `rand-descents` (the paper's RandDescents) restarts descents from uniform random starts,
//    each ending after max_steps episodes or when the loss failed to improve `patience` times
//    in a row.
// A failed episode (+infinity) sends the descent back to its best point with half the step size.
#include <memory>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "optimizers/core/adam.hpp"
#include "optimizers/core/knobs.hpp"
#include "optimizers/core/optimizer.hpp"

namespace dsb {

struct DescentConfig {
  AdamConfig adam;  // lr 0.1 (design)
  bool random_starts = false;
  int max_steps = 0;             // episodes per descent; 0 = until the budget ends
  int patience = 0;              // stop a descent after this many non-improving steps; 0 = never
  double min_improvement = 0.0;  // relative improvement that counts as progress
  double start_scale = 1.0;      // random starts uniform in [-start_scale, start_scale]^d (1 = the box)
  void validate(const std::string& owner) const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(adam, random_starts, max_steps, patience, min_improvement, start_scale)
};

DescentConfig gd_defaults();             // centre start, whole budget
DescentConfig rand_descents_defaults();  // random starts, 100 steps, patience 10, lr 0.03 (chosen here)

std::unique_ptr<Optimizer> make_gd(const DescentConfig& cfg = gd_defaults());
std::unique_ptr<Optimizer> make_rand_descents(const DescentConfig& cfg = rand_descents_defaults());
// the fields `--set gd.KEY=VALUE` / `--set rand-descents.KEY=VALUE` may set: lr (Adam's),
// max_steps, patience, min_improvement, start_scale (rand-descents only)
KnobTable descent_knobs(const std::string& owner, DescentConfig& cfg);
std::unique_ptr<Optimizer> make_gd_with(const KnobSettings& settings);
std::unique_ptr<Optimizer> make_rand_descents_with(const KnobSettings& settings);

}  // namespace dsb
