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
  double two_mu[kLaneChunk];     // 2 mu
  double lambda[kLaneChunk];
  double yield[kLaneChunk];      // yield stress (plastic)
  double threshold[kLaneChunk];  // yield / (2 mu): the flow starts where |eps^| exceeds it
  double plastic[kLaneChunk];    // 1: von Mises return mapping, 0: elastic
  double stress_scale[kLaneChunk];  // -(4 dt V_p / dx^2)
  double mass[kLaneChunk];
  // out: F_new, A = stress_scale tau + m C, and the SVD of F_tmp (for the tape)
  double F_new[9][kLaneChunk], A[9][kLaneChunk];
  double U[9][kLaneChunk], sigma[3][kLaneChunk], V[9][kLaneChunk];
  // scratch of the return mapping: the arguments and values of the logarithms and exponentials,
  // and which lanes flow (1) or not (0)
  double args[3][kLaneChunk], values[3][kLaneChunk], flow[kLaneChunk];
};

struct LaneKernels {
  // the solid update of every lane: F_tmp = (I + dt C) F, its SVD, the return mapping, F_new,
  // the Kirchhoff stress and A
  void (*solid_stress)(SolidChunk& chunk, double dt);
};

// the table of an instruction set; LanePath::scalar has none (nullptr)
const LaneKernels* lane_kernels(LanePath path);
const LaneKernels& sse2_lane_kernels();  // lanes_sse2.cpp
const LaneKernels& avx2_lane_kernels();  // lanes_avx2.cpp

}  // namespace dsb::mpm
