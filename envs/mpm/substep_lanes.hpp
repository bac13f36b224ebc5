#pragma once
// The phases of a substep (substep.hpp) on the lanes path (lane_path.hpp): the same work as the
// scalar phases of substep.cpp and substep_adjoint.cpp, with the per-particle arithmetic in the
// kernels of lane_chunks.hpp, and the same bits.
#include "common/thread_team.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/mpm_workspace.hpp"

namespace dsb::mpm {

// substep.cpp's stress phase: A_p and the new F (solids, in chunks of kLaneChunk) or J (fluids,
// one at a time as on the scalar path) of every particle; the SVD records when tape is given.
void stress_phase_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, SubstepTape* tape,
                        const LaneKernels& kernels);

// substep.cpp's P2G (colour by colour, each thread's particles in the scalar order, in chunks)
void p2g_lanes(const MpmModel& model, MpmWorkspace& ws, const ParticleBins& bins, ThreadTeam& team,
               const LaneKernels& kernels);

// substep.cpp's G2P and advection
void g2p_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const LaneKernels& kernels);

// substep_adjoint.cpp's G2P^T: the advection's adjoint of every particle (ws.advection) and the
// coloured scatter into ws.grid_adj
void g2p_adjoint_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const SubstepTape& tape,
                       const std::vector<Particle>& after, const LaneKernels& kernels);

// The grid constants of the transfers, as the scalar code computes them
TransferGrid transfer_grid(const MpmModel& model);

}  // namespace dsb::mpm
