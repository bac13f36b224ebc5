#include "envs/mpm/substep_lanes.hpp"

#include <array>
#include <vector>

#include "common/parallel.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/svd3.hpp"

namespace dsb::mpm {

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

void gather_solid(SolidChunk& c, int l, const Particle& P, const SolidConstants& k, double stress_scale, double mass) {
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

namespace {

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

void pad_solid_adjoint(SolidAdjointChunk& c) {
  SolidChunk& s = c.stress;
  for (int l = c.count; l < kLaneChunk; ++l) {
    for (int e = 0; e < 9; ++e) {
      s.C[e][l] = s.C[e][0];
      s.F[e][l] = s.F[e][0];
      s.U[e][l] = s.U[e][0];
      s.V[e][l] = s.V[e][0];
      c.adj_C[e][l] = c.adj_C[e][0];
      c.adj_F[e][l] = c.adj_F[e][0];
    }
    for (int a = 0; a < 3; ++a) {
      s.sigma[a][l] = s.sigma[a][0];
      c.x[a][l] = c.x[a][0];
      c.v[a][l] = c.v[a][0];
      c.v_new[a][l] = c.v_new[a][0];
      c.adv_x[a][l] = c.adv_x[a][0];
      c.adv_v[a][l] = c.adv_v[a][0];
    }
    s.two_mu[l] = s.two_mu[0];
    s.lambda[l] = s.lambda[0];
    s.yield[l] = s.yield[0];
    s.threshold[l] = s.threshold[0];
    s.plastic[l] = s.plastic[0];
    s.stress_scale[l] = s.stress_scale[0];
    s.mass[l] = s.mass[0];
  }
}

TransferGrid transfer_grid(const MpmModel& model) {
  const MpmConfig& cfg = model.config;
  const GridLayout& L = model.layout;
  TransferGrid g;
  g.dx = cfg.dx;
  g.inv_dx = 1.0 / cfg.dx;
  g.dt = cfg.dt;
  for (int a = 0; a < 3; ++a) {
    // as make_stencil (kernel.hpp)
    g.stencil_low[a] = -static_cast<double>(L.pad);
    g.stencil_top[a] = static_cast<double>(L.n[a] - 3 - L.pad);
    g.clamp_high[a] = cfg.clamp_high(a);
  }
  g.pad = L.pad;
  g.n1 = L.n[1];
  g.n2 = L.n[2];
  g.clamp_low = cfg.clamp_low();
  return g;
}

namespace {

// the workspace's transfer chunks, at least one per thread of the team, all empty
std::vector<TransferChunk>& empty_thread_chunks(MpmWorkspace& ws, const ThreadTeam& team) {
  std::vector<TransferChunk>& chunks = ws.lane_chunks;
  if (chunks.size() < static_cast<std::size_t>(team.size())) chunks.resize(team.size());
  for (TransferChunk& c : chunks) c.count = 0;
  return chunks;
}

// lanes past the chunk's particles repeat its first particle (finite; their results are not read)
void pad_transfer(TransferChunk& c, bool with_momentum) {
  for (int l = c.count; l < kLaneChunk; ++l) {
    for (int a = 0; a < 3; ++a) c.x[a][l] = c.x[a][0];
    if (!with_momentum) continue;
    for (int a = 0; a < 3; ++a) c.v[a][l] = c.v[a][0];
    for (int e = 0; e < 9; ++e) c.A[e][l] = c.A[e][0];
    c.mass[l] = c.mass[0];
  }
}

}  // namespace

void p2g_lanes(const MpmModel& model, MpmWorkspace& ws, const ParticleBins& bins, ThreadTeam& team,
               const LaneKernels& kernels) {
  const TransferGrid g = transfer_grid(model);
  double* mq = ws.grid.mq.data()->data();
  // one chunk per thread, finished at the end of the thread's part of each colour
  std::vector<TransferChunk>& chunks = empty_thread_chunks(ws, team);
  auto finish = [&](int t) {
    TransferChunk& c = chunks[t];
    if (c.count == 0) return;
    pad_transfer(c, true);
    kernels.p2g(c, g, mq);
    c.count = 0;
  };
  for_each_particle_by_colour(
      bins, team,
      [&](int p, int t) {
        TransferChunk& c = chunks[t];
        const int l = c.count;
        const Particle& P = ws.particles[p];
        const Mat3& A = ws.affine[p];
        for (int a = 0; a < 3; ++a) {
          c.x[a][l] = P.x[a];
          c.v[a][l] = P.v[a];
        }
        for (int e = 0; e < 9; ++e) c.A[e][l] = A.data()[e];
        c.mass[l] = model.mass[p];
        if (++c.count == kLaneChunk) finish(t);
      },
      finish,
      [&](int q) {
        __builtin_prefetch(&ws.particles[q]);
        __builtin_prefetch(&ws.affine[q]);
        __builtin_prefetch(reinterpret_cast<const char*>(&ws.affine[q]) + 64);
      });
}

void g2p_adjoint_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const SubstepTape& tape,
                       const std::vector<Particle>& after, const LaneKernels& kernels) {
  const TransferGrid g = transfer_grid(model);
  double* vb = ws.grid_adj.v.data()->data();
  std::vector<TransferChunk>& chunks = empty_thread_chunks(ws, team);
  auto finish = [&](int t) {
    TransferChunk& c = chunks[t];
    if (c.count == 0) return;
    for (int l = c.count; l < kLaneChunk; ++l) {
      for (int a = 0; a < 3; ++a) {
        c.x[a][l] = c.x[a][0];
        c.v_new[a][l] = c.v_new[a][0];
        c.adj_x[a][l] = c.adj_x[a][0];
        c.adj_v[a][l] = c.adj_v[a][0];
      }
      for (int e = 0; e < 9; ++e) c.adj_C[e][l] = c.adj_C[e][0];
    }
    kernels.g2p_adjoint(c, g, vb);
    for (int l = 0; l < c.count; ++l) {
      AdvectionAdjoint& adv = ws.advection[c.index[l]];
      for (int a = 0; a < 3; ++a) {
        adv.x_bar[a] = c.x_bar[a][l];
        adv.v_bar[a] = c.v_bar[a][l];
      }
    }
    c.count = 0;
  };
  for_each_particle_by_colour(
      tape.bins, team,
      [&](int p, int t) {
        TransferChunk& c = chunks[t];
        const int l = c.count;
        c.index[l] = p;
        const ParticleAdjoint& a = ws.adj[p];
        for (int d = 0; d < 3; ++d) {
          c.x[d][l] = tape.before[p].x[d];
          c.v_new[d][l] = after[p].v[d];
          c.adj_x[d][l] = a.x[d];
          c.adj_v[d][l] = a.v[d];
        }
        for (int e = 0; e < 9; ++e) c.adj_C[e][l] = a.C.data()[e];
        if (++c.count == kLaneChunk) finish(t);
      },
      finish,
      [&](int q) {
        __builtin_prefetch(&tape.before[q]);
        __builtin_prefetch(&after[q]);
        __builtin_prefetch(&ws.adj[q]);
        __builtin_prefetch(reinterpret_cast<const char*>(&ws.adj[q]) + 64);
      });
}

void g2p_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const LaneKernels& kernels) {
  const TransferGrid g = transfer_grid(model);
  const double* gv = ws.grid.v.data()->data();
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    TransferChunk c;
    for (std::int64_t first = begin; first < end; first += kLaneChunk) {
      c.count = static_cast<int>(std::min<std::int64_t>(kLaneChunk, end - first));
      for (int l = 0; l < c.count; ++l)
        for (int a = 0; a < 3; ++a) c.x[a][l] = ws.particles[first + l].x[a];
      pad_transfer(c, false);
      kernels.g2p(c, g, gv);
      for (int l = 0; l < c.count; ++l) {
        Particle& P = ws.particles[first + l];
        for (int a = 0; a < 3; ++a) {
          P.v[a] = c.v_new[a][l];
          P.x[a] = c.x_new[a][l];
        }
        for (int e = 0; e < 9; ++e) P.C.data()[e] = c.C_new[e][l];
      }
    }
  });
}

}  // namespace dsb::mpm
