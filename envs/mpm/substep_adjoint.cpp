// Reverse of one MLS-MPM substep (substep.hpp). Notation: primes are the state after the
// substep; bars are adjoints dL/d(.); w, grad w, dpos = x_i - x_p = (o - fx) dx belong to the
// particle's stencil at the start of the substep.
#include <algorithm>
#include <array>
#include <cmath>

#include "common/parallel.hpp"
#include "envs/mpm/kernel.hpp"
#include "envs/mpm/substep.hpp"
#include "envs/mpm/substep_lanes.hpp"

namespace dsb::mpm {

namespace {

// Pose adjoints of every primitive at f and f + 1, summed over a range of grid blocks.
struct ContactAdjointSum {
  std::array<PoseAdjoint, kMaxPrimitives> at_f{}, at_f1{};
};

ContactAdjointSum add(ContactAdjointSum a, const ContactAdjointSum& b) {
  for (int i = 0; i < kMaxPrimitives; ++i) {
    a.at_f[i] += b.at_f[i];
    a.at_f1[i] += b.at_f1[i];
  }
  return a;
}

// x' = clamp(x + dt v'): where not clamped, x'_bar reaches x and dt x'_bar reaches v'
AdvectionAdjoint advection_adjoint(const MpmConfig& cfg, const Vec3& x, const Vec3& v_new, const ParticleAdjoint& a) {
  AdvectionAdjoint r;
  const Vec3 x_new = x + cfg.dt * v_new;
  for (int d = 0; d < 3; ++d) {
    const bool inside = x_new[d] >= cfg.clamp_low() && x_new[d] <= cfg.clamp_high(d);
    r.x_bar[d] = inside ? a.x[d] : 0.0;
  }
  r.v_bar = a.v + cfg.dt * r.x_bar;
  return r;
}

// A. G2P^T: node v_bar += w (v'_bar + (4 / dx^2) C'_bar dpos), a coloured scatter (grid.hpp).
// Keeps each particle's advection adjoint for D.
void g2p_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const SubstepTape& tape,
                 const std::vector<Particle>& after) {
  const MpmConfig& cfg = model.config;
  const double inv_dx = 1.0 / cfg.dx;
  const GridLayout& L = model.layout;
  const ParticleBins& bins = tape.bins;
  std::vector<Vec3>& vb = ws.grid_adj.v;
  for_each_particle_by_colour(bins, team, [&](int p) {
    const Vec3& x = tape.before[p].x;
    const Stencil s = make_stencil(x, inv_dx, L);
    const AdvectionAdjoint adv = advection_adjoint(cfg, x, after[p].v, ws.adj[p]);
    ws.advection[p] = adv;
    // (4 / dx^2) C'_bar dpos = (4 / dx) C'_bar (o - fx)
    const Mat3 Cs = (4.0 * inv_dx) * ws.adj[p].C;
    const Vec3 base_term = adv.v_bar - Cs * s.fx;
    const Vec3 c0 = Cs.col(0), c1 = Cs.col(1), c2 = Cs.col(2);
    scatter_affine(s, L, base_term, c0, c1, c2, vb);
  });
}

// B. grid update^T on the active blocks: node v_bar -> q_bar, m_bar, written over the restored
// q and m; contact pose adjoints summed over blocks in block order.
ContactAdjointSum grid_update_adjoint(const MpmModel& model, MpmWorkspace& ws, const ParticleBins& bins,
                                      ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const GridLayout& L = model.layout;
  GridFields& g = ws.grid;
  const std::vector<Vec3>& vb = ws.grid_adj.v;
  const std::vector<int>& active = bins.active;
  const Vec3 dv_gravity = cfg.dt * cfg.gravity;
  const int np = static_cast<int>(model.primitives.size());
  auto fold = [&](std::int64_t begin, std::int64_t end, ContactAdjointSum acc) {
    std::array<Vec3, kMaxPrimitives + 1> vs;
    for (std::int64_t bb = begin; bb < end; ++bb)
      for_each_node_of_block(L, active[bb], [&](int i, int j, int k, int n) {
        const double m = g.mq[n].w();
        if (!(m > cfg.grid_mass_epsilon)) {  // v = 0: nothing flows back
          g.mq[n].setZero();
          return;
        }
        // forward again: v_0 = q / m + dt g, then each primitive
        const Vec3 q_over_m = g.mq[n].head<3>() / m;
        const Vec3 x((i - L.pad) * cfg.dx, (j - L.pad) * cfg.dx, (k - L.pad) * cfg.dx);
        vs[0] = q_over_m + dv_gravity;
        for (int pr = 0; pr < np; ++pr) vs[pr + 1] = collide(model.primitives[pr], ws.frames[pr], x, vs[pr]);
        const int I[3] = {i - L.pad, j - L.pad, k - L.pad};  // position indices
        Vec3 bar = apply_boundary_adjoint(cfg, I, vs[np], vb[n]);
        for (int pr = np - 1; pr >= 0; --pr)
          bar = collide_adjoint(model.primitives[pr], ws.frames[pr], x, vs[pr], bar, acc.at_f[pr], acc.at_f1[pr]);
        // v_0 = q / m + dt g: (dL/dq, dL/dm) over (q, m)
        g.mq[n] << bar / m, -bar.dot(q_over_m) / m;
      });
    return acc;
  };
  return parallel_reduce<ContactAdjointSum>(team, static_cast<std::int64_t>(active.size()), kBlockGrain,
                                            ContactAdjointSum{}, ContactAdjointSum{}, fold, add);
}

// D. per particle: the stress update again from `before` and the recorded SVD (U restored, the
// return mapping recomputed in batches), then the P2G^T gather, G2P's position terms and the
// stress adjoint. Node sums go by axis (the z sums first) to share the weights' products.

// What every particle's reverse reads.
struct ParticleAdjointContext {
  const MpmModel& model;
  MpmWorkspace& ws;
  const SubstepTape& tape;
  const std::vector<Particle>& after;
  const LaneKernels* lanes;  // the P2G^T gather's kernel on the lanes path, else nullptr
  TransferGrid lane_grid;
};

// The reverse of particle p, whose stress update gave the Kirchhoff stress tau, with its tape
// (solids) or none (fluids)
void adjoint_of_particle(const ParticleAdjointContext& ctx, std::int64_t p, const Mat3& tau, const SolidTape* solid) {
  const MpmModel& model = ctx.model;
  MpmWorkspace& ws = ctx.ws;
  const SubstepTape& tape = ctx.tape;
  const std::vector<Particle>& after = ctx.after;
  const LaneKernels* lanes = ctx.lanes;
  const TransferGrid& lane_grid = ctx.lane_grid;
  const MpmConfig& cfg = model.config;
  const double dx = cfg.dx, inv_dx = 1.0 / dx;
  const double k_dt = 4.0 * cfg.dt / (dx * dx);
  const GridLayout& L = model.layout;
  const std::vector<Vec3>& gv = ws.grid.v;    // node velocities after the grid update
  const std::vector<Vec4>& qmb = ws.grid.mq;  // now (dL/dq, dL/dm)
  const Particle& P = tape.before[p];
  const ParticleAdjoint& a = ws.adj[p];
  const AdvectionAdjoint& adv = ws.advection[p];
  ParticleAdjoint& out = ws.adj_prev[p];
  const Material& mat = model.materials[model.material_of[p]];
  const double mp = model.mass[p];
  const double k_stress = k_dt * model.volume[p];
  // A = -k tau + m C
  const Mat3 A = -k_stress * tau + mp * P.C;
  const Vec3& v_new = after[p].v;
  const Stencil s = make_stencil(P.x, inv_dx, L);
  const Mat3 Cs = (4.0 * inv_dx * inv_dx) * a.C;  // (4 / dx^2) C'_bar
  // per node n (offset o): the scalar whose product with grad w_n is x_bar's share,
  //   m_bar m_p + q_bar . (m v + A dpos) + v_n . (C_s dpos + v'_bar)
  // with m v + A dpos = t0 + dx A o and C_s dpos + v'_bar = u0 + dx C_s o
  // (t, m_p) as a 4-vector, so that m_bar m_p + q_bar . t is one dot product with (q_bar, m_bar)
  Vec4 t0, ad0, ad1, ad2;
  t0 << mp * P.v - dx * (A * s.fx), mp;
  ad0 << dx * A.col(0), 0.0;
  ad1 << dx * A.col(1), 0.0;
  ad2 << dx * A.col(2), 0.0;
  const Vec3 u0 = adv.v_bar - dx * (Cs * s.fx);
  const Vec3 cd0 = dx * Cs.col(0), cd1 = dx * Cs.col(1), cd2 = dx * Cs.col(2);
  Vec3 x_bar = Vec3::Zero();
  Vec3 sum_wq = Vec3::Zero();  // sum w q_bar
  Mat3 Mq = Mat3::Zero();      // sum w q_bar o^T
  if (lanes) {
    // the same sums on the lanes path (adjoint_lanes.hpp)
    GatherTerms terms;
    terms.corner = L.node(s.base[0], s.base[1], s.base[2]);
    for (int a = 0; a < 3; ++a)
      for (int o = 0; o < 3; ++o) {
        terms.w[a][o] = s.w[a][o];
        terms.dw[a][o] = s.dw[a][o];
      }
    const Vec4* ad[3] = {&ad0, &ad1, &ad2};
    const Vec3* cd[3] = {&cd0, &cd1, &cd2};
    for (int e = 0; e < 4; ++e) {
      terms.t0[e] = t0[e];
      for (int k = 0; k < 3; ++k) terms.ad[k][e] = (*ad[k])[e];
    }
    for (int e = 0; e < 3; ++e) {
      terms.u0[e] = u0[e];
      for (int k = 0; k < 3; ++k) terms.cd[k][e] = (*cd[k])[e];
    }
    GatherSums sums;
    lanes->p2g_adjoint_gather(terms, lane_grid, qmb.data()->data(), gv.data()->data(), sums);
    x_bar = Vec3(sums.x_bar[0], sums.x_bar[1], sums.x_bar[2]);
    sum_wq = Vec3(sums.sum_wq[0], sums.sum_wq[1], sums.sum_wq[2]);
    for (int e = 0; e < 9; ++e) Mq.data()[e] = sums.Mq[e];
  }
  for (int i = 0; i < 3 && !lanes; ++i) {
    const Vec4 ti = t0 + static_cast<double>(i) * ad0;
    const Vec3 ui = u0 + static_cast<double>(i) * cd0;
    for (int j = 0; j < 3; ++j) {
      const Vec4 tij = ti + static_cast<double>(j) * ad1;
      const Vec3 uij = ui + static_cast<double>(j) * cd1;
      const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
      double S0 = 0.0, S1 = 0.0;                  // sum_k w_z s, sum_k w_z' s
      Vec3 Q0 = Vec3::Zero(), Qk = Vec3::Zero();  // sum_k w_z q_bar, sum_k k w_z q_bar
      for (int k = 0; k < 3; ++k) {
        const int nd = row + k;
        const double sc =
            qmb[nd].dot(tij + static_cast<double>(k) * ad2) + gv[nd].dot(uij + static_cast<double>(k) * cd2);
        S0 += s.w[2][k] * sc;
        S1 += s.dw[2][k] * sc;
        const Vec3 wq = s.w[2][k] * qmb[nd].head<3>();
        Q0 += wq;
        Qk += static_cast<double>(k) * wq;
      }
      const double wxy = s.w[0][i] * s.w[1][j];
      x_bar += Vec3(s.dw[0][i] * s.w[1][j] * S0, s.w[0][i] * s.dw[1][j] * S0, wxy * S1);
      sum_wq += wxy * Q0;
      Mq.col(0) += (wxy * i) * Q0;
      Mq.col(1) += (wxy * j) * Q0;
      Mq.col(2) += wxy * Qk;
    }
  }
  // G2P's C' through dpos = x_i - x_p: -C_s^T v'; advection; P2G's q through dpos: -A^T sum w q_bar
  x_bar += adv.x_bar - Cs.transpose() * v_new - A.transpose() * sum_wq;
  out.x = x_bar;
  // q_i = sum w (m v + A dpos)
  out.v = mp * sum_wq;
  const Mat3 A_bar = dx * (Mq - sum_wq * s.fx.transpose());  // sum w q_bar dpos^T
  // A = -k tau + m C
  const Mat3 tau_bar = -k_stress * A_bar;
  out.C = mp * A_bar;
  if (!solid) {
    out.J = fluid_update_adjoint(mat, P.C, P.J, cfg.dt, tau_bar, a.J, out.C);
    out.F = a.F;  // F is not used by fluids
  } else {
    solid_update_adjoint(mat, P.C, P.F, cfg.dt, *solid, tau_bar, a.F, out.C, out.F);
    out.J = a.J;  // J is not used by solids
  }
}

void particle_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const SubstepTape& tape,
                      const std::vector<Particle>& after) {
  const MpmConfig& cfg = model.config;
  const ParticleAdjointContext ctx{model, ws, tape, after, nullptr, transfer_grid(model)};
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    std::array<SolidTape, kSolidBatch> tapes;
    std::array<Mat3, kSolidBatch> F, tau_solid;
    std::array<const Material*, kSolidBatch> mats;
    std::array<int, kSolidBatch> slot_of;  // particle offset in the chunk -> solid slot
    for (std::int64_t chunk = begin; chunk < end; chunk += kSolidBatch) {
      const std::int64_t chunk_end = std::min(end, chunk + kSolidBatch);
      // the solids' stress update, again
      int n = 0;
      for (std::int64_t p = chunk; p < chunk_end; ++p) {
        const Material& mat = model.materials[model.material_of[p]];
        slot_of[p - chunk] = -1;
        if (mat.kind == MaterialKind::fluid) continue;
        F[n] = trial_deformation(tape.before[p].C, cfg.dt, tape.before[p].F);
        tapes[n].svd = restore_svd(tape.svd[p], F[n]);
        mats[n] = &mat;
        slot_of[p - chunk] = n++;
      }
      solid_update_batch(mats.data(), F.data(), tapes.data(), tau_solid.data(), n);
      for (std::int64_t p = chunk; p < chunk_end; ++p) {
        const int slot = slot_of[p - chunk];
        if (slot >= 0) {
          adjoint_of_particle(ctx, p, tau_solid[slot], &tapes[slot]);
        } else {
          double J_new = tape.before[p].J;
          const Mat3 tau = fluid_update(model.materials[model.material_of[p]], tape.before[p].C, cfg.dt, J_new);
          adjoint_of_particle(ctx, p, tau, nullptr);
        }
      }
    }
  });
}

// The same on the lanes path: the solids in chunks through the solid_adjoint kernel (the SVD
// restored here, particle by particle, as above), the fluids one at a time as above with the
// lanes gather.
void particle_adjoint_lanes(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const SubstepTape& tape,
                            const std::vector<Particle>& after, const LaneKernels& kernels) {
  const MpmConfig& cfg = model.config;
  const ParticleAdjointContext ctx{model, ws, tape, after, &kernels, transfer_grid(model)};
  const double k_dt = 4.0 * cfg.dt / (cfg.dx * cfg.dx);
  const double* qmb = ws.grid.mq.data()->data();
  const double* gv = ws.grid.v.data()->data();
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    SolidAdjointChunk c;
    std::array<std::int64_t, kLaneChunk> index;
    SolidConstants constants;
    auto finish = [&] {
      pad_solid_adjoint(c);
      kernels.solid_adjoint(c, ctx.lane_grid, qmb, gv);
      for (int l = 0; l < c.count; ++l) {
        ParticleAdjoint& out = ws.adj_prev[index[l]];
        for (int a = 0; a < 3; ++a) {
          out.x[a] = c.out_x[a][l];
          out.v[a] = c.out_v[a][l];
        }
        for (int e = 0; e < 9; ++e) {
          out.C.data()[e] = c.out_C[e][l];
          out.F.data()[e] = c.out_F[e][l];
        }
        out.J = ws.adj[index[l]].J;  // J is not used by solids
      }
      c.count = 0;
    };
    c.count = 0;
    // the tapes are larger than the caches: fetch the particles a few places ahead (written out
    // here: in a lambda of its own, GCC found no side effect and dropped the calls)
    constexpr std::int64_t kAheadParticles = 6;
    for (std::int64_t p = begin; p < end; ++p) {
      if (const std::int64_t q = p + kAheadParticles; q < end) {
        for (int line = 0; line < 4; ++line) {
          __builtin_prefetch(reinterpret_cast<const char*>(&tape.before[q]) + 64 * line);
          __builtin_prefetch(reinterpret_cast<const char*>(&ws.adj[q]) + 64 * line);
        }
        __builtin_prefetch(&after[q].v);
        __builtin_prefetch(&ws.advection[q]);
        __builtin_prefetch(&tape.svd[q]);
      }
      const int material = model.material_of[p];
      const Particle& P = tape.before[p];
      if (model.materials[material].kind == MaterialKind::fluid) {
        double J_new = P.J;
        const Mat3 tau = fluid_update(model.materials[material], P.C, cfg.dt, J_new);
        adjoint_of_particle(ctx, p, tau, nullptr);
        continue;
      }
      if (constants.material != material) constants = solid_constants(model, material);
      const int l = c.count;
      index[l] = p;
      gather_solid(c.stress, l, P, constants, -(k_dt * model.volume[p]), model.mass[p]);
      const Svd3 svd = restore_svd(tape.svd[p], trial_deformation(P.C, cfg.dt, P.F));
      for (int e = 0; e < 9; ++e) {
        c.stress.U[e][l] = svd.U.data()[e];
        c.stress.V[e][l] = svd.V.data()[e];
      }
      for (int a = 0; a < 3; ++a) c.stress.sigma[a][l] = svd.sigma[a];
      const ParticleAdjoint& a = ws.adj[p];
      const AdvectionAdjoint& adv = ws.advection[p];
      for (int d = 0; d < 3; ++d) {
        c.x[d][l] = P.x[d];
        c.v[d][l] = P.v[d];
        c.v_new[d][l] = after[p].v[d];
        c.adv_x[d][l] = adv.x_bar[d];
        c.adv_v[d][l] = adv.v_bar[d];
      }
      for (int e = 0; e < 9; ++e) {
        c.adj_C[e][l] = a.C.data()[e];
        c.adj_F[e][l] = a.F.data()[e];
      }
      if (++c.count == kLaneChunk) finish();
    }
    if (c.count > 0) finish();
  });
}

}  // namespace

void substep_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions,
                     const SubstepTape& tape, const std::vector<Particle>& after, double* actions_bar) {
  const MpmConfig& cfg = model.config;
  const int np = static_cast<int>(model.primitives.size());
  PhaseClock clock(ws.phase_times);
  tape.grid.restore(model.layout, ws.grid, team);
  clear_blocks(model.layout, tape.bins.active, ws.grid_adj, team);
  for (int pr = 0; pr < np; ++pr) {
    const PrimitiveSpec& spec = model.primitives[pr];
    ws.next_poses[pr] = advance_pose(spec, tape.poses[pr], actions + model.action_offset(pr), cfg.substeps);
    ws.frames[pr] = contact_frame(spec, tape.poses[pr], ws.next_poses[pr], cfg.dt);
  }
  clock.lap(&PhaseTimes::reverse_grid);
  if (const LaneKernels* lanes = lane_kernels(ws.lanes))
    g2p_adjoint_lanes(model, ws, team, tape, after, *lanes);
  else
    g2p_adjoint(model, ws, team, tape, after);
  clock.lap(&PhaseTimes::reverse_g2p);
  const ContactAdjointSum contact = grid_update_adjoint(model, ws, tape.bins, team);
  // C. kinematics: pose f+1's adjoint (later substeps + this contact) back to pose f
  for (int pr = 0; pr < np; ++pr) {
    PoseAdjoint bar = ws.pose_adj[pr];
    bar += contact.at_f1[pr];
    advance_pose_adjoint(model.primitives[pr], tape.poses[pr], actions + model.action_offset(pr), cfg.substeps, bar,
                         actions_bar + model.action_offset(pr));
    bar += contact.at_f[pr];
    ws.pose_adj[pr] = bar;
  }
  clock.lap(&PhaseTimes::reverse_grid);
  if (const LaneKernels* lanes = lane_kernels(ws.lanes))
    particle_adjoint_lanes(model, ws, team, tape, after, *lanes);
  else
    particle_adjoint(model, ws, team, tape, after);
  ws.adj.swap(ws.adj_prev);
  clock.lap(&PhaseTimes::reverse_particles);
}

}  // namespace dsb::mpm
