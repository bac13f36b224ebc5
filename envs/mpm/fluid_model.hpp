#pragma once
#include <limits>
// The `fluid` task (fluid_config.hpp) as an MPM model, and its loss.
#include "envs/mpm/episode.hpp"
#include "envs/mpm/fluid_config.hpp"
#include "envs/mpm/mpm_model.hpp"

namespace dsb::mpm {

// Bodies: 0 = cube (first in the particle arrays), 1 = syrup. Primitives: 0 = bowl, 1 = handle,
// both translating along x and y with the same two actions.
MpmModel build_fluid_model(const FluidConfig& cfg);

// Where the cube is: the mean of its particles' positions.
Vec3 cube_centre(const MpmModel& model, const std::vector<Particle>& particles);

// The seed's loss on the state after the last env step (0 after the others):
//   max(0, rim_height - (y_cube - floor)) + w_l |xz_cube - xz_bowl| + w_a |xz_cube - xz_axis|
class FluidObjective : public EpisodeObjective {
 public:
  FluidObjective(const FluidConfig& cfg, const MpmModel& model) : cfg_(cfg), model_(model) {}
  double step_loss(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                   ThreadTeam& team) const override;
  void step_loss_adjoint(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                         std::vector<ParticleAdjoint>& adj, std::vector<PoseAdjoint>& pose_adj,
                         ThreadTeam& team) const override;
  double final_loss(const std::vector<Particle>& particles, const std::vector<Pose>& poses) const;
  // the cube centre's height above the tank floor (m) in the state `particles`
  double cube_height(const std::vector<Particle>& particles) const;
  // the cube centre's height above the tank floor after the last env step (the episode's second
  // metric: above cfg.rim_height the cube is out of the tank); NaN until that step was scored
  double final_cube_height() const { return final_cube_height_; }

 private:
  const FluidConfig& cfg_;
  const MpmModel& model_;
  mutable double final_cube_height_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace dsb::mpm
