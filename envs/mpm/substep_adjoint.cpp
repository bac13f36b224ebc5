// Reverse of one MLS-MPM substep (substep.hpp). Notation: primes are the state after the
// substep; bars are adjoints dL/d(.); w, grad w, dpos = x_i - x_p are the stencil of the
// particle's position at the start of the substep.
#include <algorithm>
#include <array>
#include <cmath>

#include "common/parallel.hpp"
#include "envs/mpm/kernel.hpp"
#include "envs/mpm/substep.hpp"

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

// dL/dv'_total = v'_bar + dt x'_bar (masked where the position was clamped), and the mask
struct AdvectionAdjoint {
  Vec3 x_bar;  // the part of x'_bar that reaches x and v'
  Vec3 v_bar;  // dL/dv' including advection
};

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

// A. G2P^T: grid v_bar += w (v'_bar + (4 / dx^2) C'_bar dpos), coloured scatter. Also stores each
// particle's G2P velocity v' (the same sum as the forward pass, so the same bits) in v_new.
void g2p_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const std::vector<Particle>& before,
                 std::vector<Vec3>& v_new) {
  const MpmConfig& cfg = model.config;
  const double inv_dx = 1.0 / cfg.dx;
  const GridLayout& L = model.layout;
  const GridFields& g = ws.grid;
  GridAdjoint& ga = ws.grid_adj;
  for (int c = 0; c < kColours; ++c) {
    const std::vector<int>& blocks = ws.bins.by_colour[c];
    parallel_for(team, static_cast<std::int64_t>(blocks.size()), 1, [&](std::int64_t bb, std::int64_t) {
      const int b = blocks[bb];
      for (int o = ws.bins.block_begin[b]; o < ws.bins.block_begin[b + 1]; ++o) {
        const int p = ws.bins.order[o];
        const Stencil s = make_stencil(before[p].x, inv_dx, L.n);
        Vec3 v = Vec3::Zero();
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const double wij = s.w[0][i] * s.w[1][j];
            const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
            for (int k = 0; k < 3; ++k) v += (wij * s.w[2][k]) * g.v[row + k];
          }
        v_new[p] = v;
        const AdvectionAdjoint adv = advection_adjoint(cfg, before[p].x, v, ws.adj[p]);
        // (4 / dx^2) C'_bar dpos = (4 / dx) C'_bar (o - fx)
        const Mat3 Cs = (4.0 * inv_dx) * ws.adj[p].C;
        const Vec3 base_term = adv.v_bar - Cs * s.fx;
        for (int i = 0; i < 3; ++i) {
          const Vec3 ti = base_term + static_cast<double>(i) * Cs.col(0);
          for (int j = 0; j < 3; ++j) {
            const Vec3 tij = ti + static_cast<double>(j) * Cs.col(1);
            const double wij = s.w[0][i] * s.w[1][j];
            const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
            for (int k = 0; k < 3; ++k) ga.v[row + k] += (wij * s.w[2][k]) * (tij + static_cast<double>(k) * Cs.col(2));
          }
        }
      }
    });
  }
}

// B. grid update^T on the active blocks: node v_bar -> q_bar, m_bar; contact pose adjoints summed
// over blocks in block order.
ContactAdjointSum grid_update_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const GridLayout& L = model.layout;
  const GridFields& g = ws.grid;
  GridAdjoint& ga = ws.grid_adj;
  const std::vector<int>& active = ws.bins.active;
  const Vec3 dv_gravity = cfg.dt * cfg.gravity;
  const int np = static_cast<int>(model.primitives.size());
  auto fold = [&](std::int64_t begin, std::int64_t end, ContactAdjointSum acc) {
    std::array<int, 3> lo, hi;
    std::array<Vec3, kMaxPrimitives + 1> vs;
    for (std::int64_t bb = begin; bb < end; ++bb) {
      L.block_range(active[bb], lo, hi);
      for (int i = lo[0]; i < hi[0]; ++i)
        for (int j = lo[1]; j < hi[1]; ++j)
          for (int k = lo[2]; k < hi[2]; ++k) {
            const int n = L.node(i, j, k);
            if (!(g.m[n] > cfg.grid_mass_epsilon)) continue;  // v = 0: nothing flows back
            // forward again: v_0 = q / m + dt g, then each primitive
            const Vec3 q_over_m = g.q[n] / g.m[n];
            const Vec3 x(i * cfg.dx, j * cfg.dx, k * cfg.dx);
            vs[0] = q_over_m + dv_gravity;
            for (int pr = 0; pr < np; ++pr) vs[pr + 1] = collide(model.primitives[pr], ws.frames[pr], x, vs[pr]);
            const int I[3] = {i, j, k};
            Vec3 bar = apply_boundary_adjoint(cfg, I, vs[np], ga.v[n]);
            for (int pr = np - 1; pr >= 0; --pr)
              bar = collide_adjoint(model.primitives[pr], ws.frames[pr], x, vs[pr], bar, acc.at_f[pr], acc.at_f1[pr]);
            // v_0 = q / m + dt g
            ga.q[n] = bar / g.m[n];
            ga.m[n] = -bar.dot(q_over_m) / g.m[n];
          }
    }
    return acc;
  };
  return parallel_reduce<ContactAdjointSum>(team, static_cast<std::int64_t>(active.size()), kBlockGrain,
                                            ContactAdjointSum{}, ContactAdjointSum{}, fold, add);
}

// D. per particle: P2G^T gather, G2P's position terms, and the stress adjoint.
void particle_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const SubstepTape& tape,
                      const std::vector<Vec3>& v_new) {
  const MpmConfig& cfg = model.config;
  const double dx = cfg.dx, inv_dx = 1.0 / dx;
  const double k_dt = 4.0 * cfg.dt / (dx * dx);
  const GridLayout& L = model.layout;
  const GridFields& g = ws.grid;
  const GridAdjoint& ga = ws.grid_adj;
  parallel_for(team, model.particles(), kParticleGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      const Particle& P = tape.before[p];
      const ParticleAdjoint& a = ws.adj[p];
      ParticleAdjoint& out = ws.adj_prev[p];
      const Material& mat = model.materials[model.material_of[p]];
      const double mp = model.mass[p];
      const double k_stress = k_dt * model.volume[p];
      // the forward affine momentum A = -k tau + m C
      Mat3 tau;
      double J_new = P.J;
      if (mat.kind == MaterialKind::fluid)
        tau = fluid_update(mat, P.C, cfg.dt, J_new);
      else
        tau = solid_stress(mat, tape.solid[p]);
      const Mat3 A = -k_stress * tau + mp * P.C;
      const Stencil s = make_stencil(P.x, inv_dx, L.n);
      const Vec3 mv = mp * P.v;
      const Mat3 Cs = (4.0 * inv_dx * inv_dx) * a.C;  // (4 / dx^2) C'_bar
      Vec3 sum_wq = Vec3::Zero();   // sum w q_bar
      Mat3 A_bar = Mat3::Zero();    // sum w q_bar dpos^T
      Mat3 Gv = Mat3::Zero();       // sum grad w v_i^T
      Vec3 x_bar = Vec3::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
          for (int k = 0; k < 3; ++k) {
            const int n = row + k;
            const double w = s.w[0][i] * s.w[1][j] * s.w[2][k];
            const Vec3 gw = weight_gradient(s, i, j, k);
            const Vec3 dpos = (Vec3(i, j, k) - s.fx) * dx;
            const Vec3& vi = g.v[n];
            const Vec3& qb = ga.q[n];
            sum_wq += w * qb;
            A_bar += (w * qb) * dpos.transpose();
            Gv += gw * vi.transpose();
            // P2G: d(w m_p)/dx, d(w (m v + A dpos))/dx through w; G2P: d(w v_i dpos^T)/dx through w
            const double scalar = ga.m[n] * mp + qb.dot(mv + A * dpos) + vi.dot(Cs * dpos);
            x_bar += scalar * gw;
          }
        }
      const AdvectionAdjoint adv = advection_adjoint(cfg, P.x, v_new[p], a);
      // G2P: v' = sum w v_i (through grad w), C' through dpos = x_i - x_p; advection x' = x + dt v'
      x_bar += Gv * adv.v_bar - Cs.transpose() * v_new[p] + adv.x_bar;
      // P2G: q through dpos = x_i - x_p
      x_bar -= A.transpose() * sum_wq;
      out.x = x_bar;
      out.v = mp * sum_wq;
      // A = -k tau + m C
      const Mat3 tau_bar = -k_stress * A_bar;
      out.C = mp * A_bar;
      if (mat.kind == MaterialKind::fluid) {
        out.J = fluid_update_adjoint(mat, P.C, P.J, cfg.dt, tau_bar, a.J, out.C);
        out.F = a.F;  // F is not used by fluids
      } else {
        solid_update_adjoint(mat, P.C, P.F, cfg.dt, tape.solid[p], tau_bar, a.F, out.C, out.F);
        out.J = a.J;  // J is not used by solids
      }
    }
  });
}

}  // namespace

void substep_adjoint(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions,
                     const SubstepTape& tape, double* actions_bar) {
  const MpmConfig& cfg = model.config;
  const int np = static_cast<int>(model.primitives.size());
  tape.grid.restore(model.layout, ws.grid);
  bin_particles(model, ws.bins, team, tape.before);
  clear_blocks(model.layout, ws.bins.active, ws.grid_adj);
  for (int pr = 0; pr < np; ++pr) {
    const PrimitiveSpec& spec = model.primitives[pr];
    ws.next_poses[pr] = advance_pose(spec, tape.poses[pr], actions + model.action_offset(pr), cfg.substeps);
    ws.frames[pr] = contact_frame(spec, tape.poses[pr], ws.next_poses[pr], cfg.dt);
  }
  std::vector<Vec3>& v_new = ws.v_new;
  g2p_adjoint(model, ws, team, tape.before, v_new);
  const ContactAdjointSum contact = grid_update_adjoint(model, ws, team);
  // C. kinematics: pose f+1's adjoint (later substeps + this contact) back to pose f
  for (int pr = 0; pr < np; ++pr) {
    PoseAdjoint bar = ws.pose_adj[pr];
    bar += contact.at_f1[pr];
    advance_pose_adjoint(model.primitives[pr], tape.poses[pr], actions + model.action_offset(pr), cfg.substeps, bar,
                         actions_bar + model.action_offset(pr));
    bar += contact.at_f[pr];
    ws.pose_adj[pr] = bar;
  }
  particle_adjoint(model, ws, team, tape, v_new);
  ws.adj.swap(ws.adj_prev);
}

}  // namespace dsb::mpm
