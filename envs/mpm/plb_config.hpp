#pragma once
// Configuration of a PlasticineLab task (`plb-NAME`, plb_tasks.hpp): PlasticineLab's simulator
// constants (its simulator), its loss weights with the contact weight raised
// (the paper's one change to the loss), the paper's action parameterization (5 segments of held
// per-manipulator commands) and the horizon. Stored with every run.
#include <cstdint>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "envs/mpm/mpm_config.hpp"
#include "envs/mpm/plb_target_file.hpp"
#include "envs/mpm/plb_tasks.hpp"

namespace dsb::mpm {

struct PlbConfig {
  std::string task;  // a name of plb_tasks()
  MpmConfig mpm = default_mpm();
  int env_steps = 50;                            // PlasticineLab's max_episode_steps
  int segments = 5;                              // the paper: 5 equal segments of held commands
  double softness = 666.0;                       // PlasticineLab's gradient solver (its RL env leaves it 0)
  double particle_volume = 0.5 / 64 * 0.5 / 64;  // PlasticineLab's p_vol = (dx / 2)^2 (its 2-D formula)
  double density = 1.0;                          // p_rho: particle mass = 6.1e-5
  double sdf_weight = 10.0;                      // PlasticineLab
  double density_weight = 10.0;                  // PlasticineLab
  double contact_weight = 1.0;                   // PlasticineLab: 1; set by plb_config() (see there)
  double target_threshold = 1e-4;                // target cells above this mass are "inside" for the SDF
  int observed_particles = 200;  // RL observation: every (N / 200)-th particle, integer division (PlasticineLab)
  std::uint64_t seed = 0;        // shape sampling (PlasticineLab samples with numpy seed 0)
  // a target read from a file (the env option `target`), in place of data/targets' generated one;
  // null: the generated one. In the stored config by the hash of its values only.
  std::shared_ptr<const PlbTargetFile> target_file;

  static MpmConfig default_mpm();
  int steps_per_segment() const { return env_steps / segments; }
  void validate() const;           // ConfigError naming the field
  nlohmann::json to_json() const;  // fields() plus the task's shapes, primitives, material and target
  // the stored fields, each named once (common/config_fields.hpp); the loss weights under "loss"
  template <class Visit>
  void fields(Visit&& visit) const {
    DSB_VISIT_FIELDS(visit, task, mpm, env_steps, segments, softness, particle_volume, density);
    visit("loss.sdf_weight", sdf_weight);
    visit("loss.density_weight", density_weight);
    visit("loss.contact_weight", contact_weight);
    visit("loss.target_threshold", target_threshold);
    DSB_VISIT_FIELDS(visit, seed, observed_particles);
  }
};

// The config of task `name` with the paper's raised contact weight (plb_config.cpp says why).
PlbConfig plb_config(const std::string& name);

}  // namespace dsb::mpm
