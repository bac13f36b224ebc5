#pragma once
// PlasticineLab's loss (its task loss) and its adjoint: after every env step
//   L_t = w_sdf sum_I d_I m_I + w_density sum_I |m_I - t_I| + w_contact sum_k (min_p max(sdf_k(x_p), 0))^2
// with m the grid mass (P2G of each particle's mass with the simulation's own B-spline), t the
// target, d the distance to the target (plb_model.hpp), k over the manipulators; the trajectory
// objective sums L_t over the env steps. The soft IoU of the last state is kept as the episode's
// second metric.
#include <limits>
#include <vector>

#include "envs/mpm/episode.hpp"
#include "envs/mpm/grid.hpp"
#include "envs/mpm/plb_config.hpp"
#include "envs/mpm/plb_model.hpp"

namespace dsb::mpm {

// The grid mass of a state, m_I = sum_p w_Ip m_p with the simulation's stencil (the colour-by-colour
// scatter of grid.hpp): `mass` is valid on `bins.active`'s nodes, zero where no stencil reaches.
void grid_mass(const MpmModel& model, const std::vector<Particle>& particles, ThreadTeam& team, ParticleBins& bins,
               std::vector<double>& mass);

// Per-rollout buffers of the loss (part of a workspace).
struct PlbLossScratch {
  std::vector<double> mass;  // grid mass per node (valid on the bins' active blocks)
  ParticleBins bins;
  double final_iou = std::numeric_limits<double>::quiet_NaN();
  explicit PlbLossScratch(const MpmModel& model);
};

// The parts of one env step's loss (unweighted), and the IoU.
struct PlbLossTerms {
  double sdf = 0.0, density = 0.0, contact = 0.0, iou = 0.0;
};

class PlbObjective : public EpisodeObjective {
 public:
  PlbObjective(const PlbModel& model, const PlbConfig& cfg, PlbLossScratch& scratch)
      : model_(model), cfg_(cfg), scratch_(scratch) {}
  double step_loss(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                   ThreadTeam& team) const override;
  void step_loss_adjoint(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                         std::vector<ParticleAdjoint>& adj, std::vector<PoseAdjoint>& pose_adj,
                         ThreadTeam& team) const override;
  // the terms of a state (grid mass computed into the scratch)
  PlbLossTerms terms(const std::vector<Particle>& particles, const std::vector<Pose>& poses, ThreadTeam& team) const;

 private:
  void grid_mass(const std::vector<Particle>& particles, ThreadTeam& team) const;
  // min_p max(sdf_k(x_p), 0) and its particle (the lowest index among ties)
  std::pair<double, int> closest(int k, const std::vector<Particle>& particles, const Pose& pose,
                                 ThreadTeam& team) const;

  const PlbModel& model_;
  const PlbConfig& cfg_;
  PlbLossScratch& scratch_;
};

}  // namespace dsb::mpm
