#pragma once
// The lanes path's kernels (lane_path.hpp) and the chunks of particles they take: structure-of-
// arrays copies of the particles' fields, field[element][lane], one lane per particle, a matrix's
// elements in Eigen's column-major order (element i + 3 j is entry (i, j)). A chunk holds
// kLaneChunk particles: one Pack<F4> (AVX2) or two Pack<F2> (SSE2) per field. Lanes past `count`
// hold harmless padding and their results are not read.
//
// One table of kernels per instruction set (lanes_sse2.cpp, lanes_avx2.cpp); the phases that use
// them are in substep_lanes.cpp.
#include "envs/mpm/lane_path.hpp"

namespace dsb::mpm {

constexpr int kLaneChunk = 8;

// The solids of one stress chunk (material.hpp's solid update and substep.hpp's affine momentum).
struct SolidChunk {
  int count = 0;
  // in: the particle's C and F, its material's constants and its stress and momentum scales
  double C[9][kLaneChunk], F[9][kLaneChunk];
  double two_mu[kLaneChunk];  // 2 mu
  double lambda[kLaneChunk];
  double yield[kLaneChunk];         // yield stress (plastic)
  double threshold[kLaneChunk];     // yield / (2 mu): the flow starts where |eps^| exceeds it
  double plastic[kLaneChunk];       // 1: von Mises return mapping, 0: elastic
  double stress_scale[kLaneChunk];  // -(4 dt V_p / dx^2)
  double mass[kLaneChunk];
  // out: F_new, A = stress_scale tau + m C, and the SVD of F_tmp (for the tape)
  double F_new[9][kLaneChunk], A[9][kLaneChunk];
  double U[9][kLaneChunk], sigma[3][kLaneChunk], V[9][kLaneChunk];
  // scratch of the return mapping: the arguments and values of the logarithms and exponentials;
  // and what the reverse pass needs (material.hpp SolidTape): which lanes flow (1) or not (0),
  // eps^, |eps^|, k (1 without flow) and the singular values f of F_new
  double args[3][kLaneChunk], values[3][kLaneChunk], flow[kLaneChunk];
  double hat[3][kLaneChunk], norm[kLaneChunk], k[kLaneChunk], f[3][kLaneChunk];
};

// The grid as the transfers see it (kernel.hpp's make_stencil, substep.cpp's P2G and G2P).
struct TransferGrid {
  double dx = 0.0, inv_dx = 0.0, dt = 0.0;
  double stencil_low[3] = {}, stencil_top[3] = {};  // the base's clamp, in position units (-pad, n - 3 - pad)
  int pad = 0;
  int n1 = 0, n2 = 0;                          // nodes along y and z: node (i, j, k) is (i n1 + j) n2 + k
  double clamp_low = 0.0, clamp_high[3] = {};  // the particles' positions after advection
};

// The particles of one P2G or G2P chunk (in the order the scalar loop takes them) and their
// quadratic B-spline stencils.
struct TransferChunk {
  int count = 0;
  int index[kLaneChunk];  // the particle of each lane, where the caller needs it
  // in: position, and for P2G velocity, affine momentum A and mass
  double x[3][kLaneChunk], v[3][kLaneChunk], A[9][kLaneChunk], mass[kLaneChunk];
  // the stencil: base node in position units (node index = base + pad), x / dx - base, weights
  // w[axis][offset] and their derivatives
  double base[3][kLaneChunk], fx[3][kLaneChunk], w[3][3][kLaneChunk], dw[3][3][kLaneChunk];
  // P2G: m v - dx A fx, and dx A
  double base_term[3][kLaneChunk], dxA[9][kLaneChunk];
  // G2P out: velocity, C and the advected, clamped position (G2P^T in: v_new = the G2P velocity)
  double v_new[3][kLaneChunk], C_new[9][kLaneChunk], x_new[3][kLaneChunk];
  // G2P^T in: dL/d(x', v', C'); out: the advection's adjoint (x_bar, v_bar), and (4 / dx) C'_bar
  double adj_x[3][kLaneChunk], adj_v[3][kLaneChunk], adj_C[9][kLaneChunk];
  double x_bar[3][kLaneChunk], v_bar[3][kLaneChunk], Cs[9][kLaneChunk];
};

// One particle of the reverse pass's P2G^T gather (substep_adjoint.cpp's particle_adjoint): its
// stencil, the node terms t = (m v - dx A fx, m) + dx A o and u = v'_bar - dx C_s fx + dx C_s o
// (o the node offset), and the sums over its 27 nodes.
struct GatherTerms {
  int corner = 0;            // node index of offset (0, 0, 0)
  double w[3][3], dw[3][3];  // the stencil's weights and derivatives, [axis][offset]
  double t0[4], ad[3][4];    // t at o = 0 and dx A e_k (with a 0 for the mass)
  double u0[3], cd[3][3];    // u at o = 0 and dx C_s e_k
};
struct GatherSums {
  double x_bar[3];   // sum over nodes of grad w times (q_bar . t + m_bar m + v_n . u)
  double sum_wq[3];  // sum w q_bar
  double Mq[9];      // sum w q_bar o^T (column-major)
};

// The reverse of one substep for the solids of one chunk (substep_adjoint.cpp's particle_adjoint):
// the stress again from the restored SVD, the P2G^T gather, G2P's position terms and the stress
// adjoint (material.cpp's solid_update_adjoint).
struct SolidAdjointChunk {
  int count = 0;
  // in: the particles before the substep (C, F, material, scales in `stress`, with U, sigma, V
  // from restore_svd), their G2P velocities, the advection's adjoint (x_bar, v_bar), dL/dC',
  // dL/dF'
  SolidChunk stress;
  double x[3][kLaneChunk], v[3][kLaneChunk], v_new[3][kLaneChunk];
  double adv_x[3][kLaneChunk], adv_v[3][kLaneChunk], adj_C[9][kLaneChunk], adj_F[9][kLaneChunk];
  // scratch: the stencil, the gather's terms (t0 = m v - dx A fx, dx A, u0 = v_bar - dx C_s fx,
  // dx C_s, C_s = (4 / dx^2) dL/dC') and its sums
  double base[3][kLaneChunk], fx[3][kLaneChunk], w[3][3][kLaneChunk], dw[3][3][kLaneChunk];
  double t0[3][kLaneChunk], dxA[9][kLaneChunk], u0[3][kLaneChunk], dxCs[9][kLaneChunk], Cs[9][kLaneChunk];
  double xg[3][kLaneChunk], sum_wq[3][kLaneChunk], Mq[9][kLaneChunk];
  // out: dL/d(x, v, C, F) before the substep
  double out_x[3][kLaneChunk], out_v[3][kLaneChunk], out_C[9][kLaneChunk], out_F[9][kLaneChunk];
};

struct LaneKernels {
  // the solid update of every lane: F_tmp = (I + dt C) F, its SVD, the return mapping, F_new,
  // the Kirchhoff stress and A
  void (*solid_stress)(SolidChunk& chunk, double dt);
  // P2G of the chunk's particles, one after another into the grid's (q, m) (4 doubles a node)
  void (*p2g)(TransferChunk& chunk, const TransferGrid& grid, double* mq);
  // G2P of the chunk's particles from the grid's velocities (3 doubles a node)
  void (*g2p)(TransferChunk& chunk, const TransferGrid& grid, const double* v);
  // G2P^T: the advection's adjoint of the chunk's particles and their scatter into the grid's
  // velocity adjoints (3 doubles a node), one after another
  void (*g2p_adjoint)(TransferChunk& chunk, const TransferGrid& grid, double* v_bar);
  // P2G^T: one particle's sums over its nodes from the grid's (q_bar, m_bar) (4 doubles a node)
  // and velocities (3)
  void (*p2g_adjoint_gather)(const GatherTerms& terms, const TransferGrid& grid, const double* qm_bar, const double* v,
                             GatherSums& sums);
  // the reverse of the chunk's solids from the grid's (q_bar, m_bar) and velocities
  void (*solid_adjoint)(SolidAdjointChunk& chunk, const TransferGrid& grid, const double* qm_bar, const double* v);
};

// the table of an instruction set; scalar (and avx: the engine offers no such lanes) has none (nullptr)
const LaneKernels* lane_kernels(SimdPath path);
const LaneKernels& sse2_lane_kernels();  // lanes_sse2.cpp
const LaneKernels& avx2_lane_kernels();  // lanes_avx2.cpp

}  // namespace dsb::mpm
