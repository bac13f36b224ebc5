#pragma once
// One MLS-MPM substep in PlasticineLab's order (its simulator's substep), and its
// reverse. Forward:
//   1. bin particles by home block; clear the active blocks;
//   2. stress: F_tmp = (I + dt C) F, SVD, return mapping, Kirchhoff stress (material.hpp), the
//      affine momentum A = -(4 dt V / dx^2) tau + m C;
//   3. P2G: m_i += w m_p, q_i += w (m_p v_p + A_p (x_i - x_p)), colour by colour (grid.hpp);
//   4. primitive kinematics, pose f -> f + 1;
//   5. grid update: v_i = q_i / m_i + dt g, primitive contact, walls and floor;
//   6. G2P: v_p = sum w v_i, C_p = (4 / dx^2) sum w v_i (x_i - x_p)^T, x_p += dt v_p (clamped).
// Reverse (substep_adjoint): G2P^T as a coloured scatter into grid adjoints, the grid update's
// adjoint per node (contact adjoints reduced over blocks in block order), the kinematics'
// adjoint, then per particle the stress update again (U restored from the tape's SVD record), the
// P2G^T gather and the stress adjoint. Every loop that sums across particles or nodes does so in
// an order that does not depend on the number of threads; loops without sums split their range
// into one part per thread (parallel_for_per_thread) to keep each part of space on one core.
#include <chrono>

#include "common/thread_team.hpp"
#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/mpm_workspace.hpp"

namespace dsb::mpm {

// Advances ws.particles and ws.poses by one substep under `actions` (the env step's actions of
// all primitives, model.action_dim() values). Records the tape when given.
void substep(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions, SubstepTape* tape);

// Reverse of the substep recorded in `tape`: on entry ws.adj / ws.pose_adj hold dL/d(state after
// the substep), on exit dL/d(state before it); dL/dactions is added to actions_bar. `after` is
// the particle state the substep produced (its velocities are the G2P velocities).
void substep_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions,
                     const SubstepTape& tape, const std::vector<Particle>& after, double* actions_bar);

// Adds the wall time since the last lap to one phase of a PhaseTimes (does nothing without one).
class PhaseClock {
 public:
  explicit PhaseClock(PhaseTimes* times);
  void lap(double PhaseTimes::*phase);

 private:
  PhaseTimes* times_;
  std::chrono::steady_clock::time_point last_;
};

// Grains of the reductions over particles and blocks (a function of the problem only, never of
// the thread count).
constexpr std::int64_t kParticleGrain = 512;
constexpr std::int64_t kBlockGrain = 8;

// Bins `particles` by home block (bins.home, order, colours, active blocks).
void bin_particles(const MpmModel& model, ParticleBins& bins, ThreadTeam& team, const std::vector<Particle>& particles);

// Wall and floor conditions of a grid node (index I) on its velocity, and their adjoint.
void apply_boundary(const MpmConfig& cfg, const int I[3], Vec3& v);
Vec3 apply_boundary_adjoint(const MpmConfig& cfg, const int I[3], const Vec3& v_in, const Vec3& v_out_bar);

}  // namespace dsb::mpm
