#pragma once
// The `fluid` scene (fluid_config.hpp) as an MPM model, and its loss.
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

 private:
  const FluidConfig& cfg_;
  const MpmModel& model_;
};

}  // namespace dsb::mpm
