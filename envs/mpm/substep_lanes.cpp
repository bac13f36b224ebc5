#include "envs/mpm/substep_lanes.hpp"

#include <array>

#include "common/parallel.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/svd3.hpp"

namespace dsb::mpm {

namespace {

// A solid material's constants as the scalar code computes them (material.cpp)
struct SolidConstants {
  int material = -1;
  double two_mu = 0.0, lambda = 0.0, yield = 0.0, threshold = 0.0, plastic = 0.0;
};

SolidConstants solid_constants(const MpmModel& model, int material) {
  const Material& mat = model.materials[material];
  SolidConstants k;
  k.material = material;
  const double mu = mat.mu();
  k.two_mu = 2.0 * mu;
  k.lambda = mat.lambda();
  k.yield = mat.yield_stress;
  k.threshold = mat.yield_stress / (2.0 * mu);
  k.plastic = mat.kind == MaterialKind::plastic ? 1.0 : 0.0;
  return k;
}

// lane l of the chunk: particle P with its material's constants and its scales
void gather_solid(SolidChunk& c, int l, const Particle& P, const SolidConstants& k, double stress_scale,
                  double mass) {
  for (int e = 0; e < 9; ++e) {
    c.C[e][l] = P.C.data()[e];
    c.F[e][l] = P.F.data()[e];
  }
  c.two_mu[l] = k.two_mu;
  c.lambda[l] = k.lambda;
  c.yield[l] = k.yield;
  c.threshold[l] = k.threshold;
  c.plastic[l] = k.plastic;
  c.stress_scale[l] = stress_scale;
  c.mass[l] = mass;
}

// lanes past the chunk's particles: an elastic particle at rest (finite, no flow)
void pad_solids(SolidChunk& c) {
  static const Particle rest;
  SolidConstants k;
  k.two_mu = 1.0;
  for (int l = c.count; l < kLaneChunk; ++l) gather_solid(c, l, rest, k, 0.0, 0.0);
}

}  // namespace

void stress_phase_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, SubstepTape* tape,
                        const LaneKernels& kernels) {
  const MpmConfig& cfg = model.config;
  const double k_stress = 4.0 * cfg.dt / (cfg.dx * cfg.dx);
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    SolidChunk chunk;
    std::array<int, kLaneChunk> index;
    SolidConstants constants;  // of the last solid material seen (bodies are contiguous)
    auto flush = [&] {
      pad_solids(chunk);
      kernels.solid_stress(chunk, cfg.dt);
      for (int l = 0; l < chunk.count; ++l) {
        const int p = index[l];
        for (int e = 0; e < 9; ++e) {
          ws.particles[p].F.data()[e] = chunk.F_new[e][l];
          ws.affine[p].data()[e] = chunk.A[e][l];
        }
        if (tape) {
          Svd3 s;
          for (int e = 0; e < 9; ++e) {
            s.U.data()[e] = chunk.U[e][l];
            s.V.data()[e] = chunk.V[e][l];
          }
          for (int a = 0; a < 3; ++a) s.sigma[a] = chunk.sigma[a][l];
          tape->svd[p] = record_svd(s);
        }
      }
      chunk.count = 0;
    };
    chunk.count = 0;
    for (std::int64_t p = begin; p < end; ++p) {
      Particle& P = ws.particles[p];
      const int material = model.material_of[p];
      const Material& mat = model.materials[material];
      if (mat.kind == MaterialKind::fluid) {
        // as the scalar path
        const Mat3 t = fluid_update(mat, P.C, cfg.dt, P.J);
        ws.affine[p] = -(k_stress * model.volume[p]) * t + model.mass[p] * P.C;
        continue;
      }
      if (constants.material != material) constants = solid_constants(model, material);
      gather_solid(chunk, chunk.count, P, constants, -(k_stress * model.volume[p]), model.mass[p]);
      index[chunk.count] = static_cast<int>(p);
      if (++chunk.count == kLaneChunk) flush();
    }
    if (chunk.count > 0) flush();
  });
}

}  // namespace dsb::mpm
