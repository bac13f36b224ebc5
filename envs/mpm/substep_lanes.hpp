#pragma once
// The phases of a substep (substep.hpp) on the lanes path (lane_path.hpp): the same work as the
// scalar phases of substep.cpp and substep_adjoint.cpp, with the per-particle arithmetic in the
// kernels of lane_chunks.hpp, and the same bits.
#include "common/thread_team.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/mpm_workspace.hpp"

namespace dsb::mpm {

// A solid material's constants as the scalar code computes them (material.cpp)
struct SolidConstants {
  int material = -1;
  double two_mu = 0.0, lambda = 0.0, yield = 0.0, threshold = 0.0, plastic = 0.0;
};
SolidConstants solid_constants(const MpmModel& model, int material);

// lane l of a solid chunk: particle P's C and F, its material's constants and its scales
void gather_solid(SolidChunk& c, int l, const Particle& P, const SolidConstants& k, double stress_scale, double mass);

// lanes past the chunk's particles repeat its first particle (finite; their results are not read)
void pad_solid_adjoint(SolidAdjointChunk& c);

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
