#include "envs/mpm/substep.hpp"

#include <algorithm>
#include <cmath>

#include "common/parallel.hpp"
#include "envs/mpm/kernel.hpp"

namespace dsb::mpm {

namespace {

// 1. stress phase: A_p and the new F (or J) of every particle. Solids' SVDs go through
// svd3_batch in chunks (the same bits as one at a time, about 3.7x faster).
void stress_phase(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, SubstepTape* tape) {
  constexpr int kChunk = 64;
  const MpmConfig& cfg = model.config;
  const double k_stress = 4.0 * cfg.dt / (cfg.dx * cfg.dx);
  parallel_for(team, model.particles(), kParticleGrain, [&](std::int64_t begin, std::int64_t end) {
    std::array<SolidTape, kChunk> scratch;
    std::array<Mat3, kChunk> F_tmp;
    std::array<Svd3, kChunk> svd;
    std::array<int, kChunk> index;
    int n = 0;
    // finish the solids gathered so far: SVDs in one batch, then return mapping and stress
    auto flush = [&] {
      svd3_batch(F_tmp.data(), svd.data(), n);
      for (int i = 0; i < n; ++i) {
        const int p = index[i];
        Particle& P = ws.particles[p];
        SolidTape& t = tape ? tape->solid[p] : scratch[i];
        t.svd = svd[i];
        P.F = F_tmp[i];
        const Mat3 tau = solid_update_from_svd(model.materials[model.material_of[p]], P.F, t);
        // A = -(4 dt V / dx^2) tau + m C
        ws.affine[p] = -(k_stress * model.volume[p]) * tau + model.mass[p] * P.C;
      }
      n = 0;
    };
    for (std::int64_t p = begin; p < end; ++p) {
      Particle& P = ws.particles[p];
      const Material& mat = model.materials[model.material_of[p]];
      if (mat.kind == MaterialKind::fluid) {
        const Mat3 tau = fluid_update(mat, P.C, cfg.dt, P.J);
        ws.affine[p] = -(k_stress * model.volume[p]) * tau + model.mass[p] * P.C;
        continue;
      }
      F_tmp[n] = trial_deformation(P.C, cfg.dt, P.F);
      index[n] = static_cast<int>(p);
      if (++n == kChunk) flush();
    }
    flush();
  });
}

}  // namespace

void bin_particles(const MpmModel& model, ParticleBins& bins, ThreadTeam& team, const std::vector<Particle>& parts) {
  const double inv_dx = 1.0 / model.config.dx;
  const GridLayout& L = model.layout;
  parallel_for(team, model.particles(), kParticleGrain * 4, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      const Stencil s = make_stencil(parts[p].x, inv_dx, L.n);
      bins.home[p] = L.block(s.base[0] >> kBlockLog2, s.base[1] >> kBlockLog2, s.base[2] >> kBlockLog2);
    }
  });
  bins.rebuild(L);
}

namespace {

// 3. P2G, colour by colour
void p2g(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const double dx = cfg.dx, inv_dx = 1.0 / dx;
  const GridLayout& L = model.layout;
  GridFields& g = ws.grid;
  for (int c = 0; c < kColours; ++c) {
    const std::vector<int>& blocks = ws.bins.by_colour[c];
    parallel_for(team, static_cast<std::int64_t>(blocks.size()), 1, [&](std::int64_t bb, std::int64_t) {
      const int b = blocks[bb];
      for (int o = ws.bins.block_begin[b]; o < ws.bins.block_begin[b + 1]; ++o) {
        const int p = ws.bins.order[o];
        const Particle& P = ws.particles[p];
        const Stencil s = make_stencil(P.x, inv_dx, L.n);
        const double mp = model.mass[p];
        const Mat3& A = ws.affine[p];
        // q_i += w (m v + A dpos), dpos = (o - fx) dx: base term and one column of dx A per axis
        const Vec3 base_term = mp * P.v - dx * (A * s.fx);
        const Vec3 a0 = dx * A.col(0), a1 = dx * A.col(1), a2 = dx * A.col(2);
        for (int i = 0; i < 3; ++i) {
          const Vec3 ti = base_term + static_cast<double>(i) * a0;
          for (int j = 0; j < 3; ++j) {
            const Vec3 tij = ti + static_cast<double>(j) * a1;
            const double wij = s.w[0][i] * s.w[1][j];
            const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
            for (int k = 0; k < 3; ++k) {
              const double w = wij * s.w[2][k];
              g.m[row + k] += w * mp;
              g.q[row + k] += w * (tij + static_cast<double>(k) * a2);
            }
          }
        }
      }
    });
  }
}

// 5. grid update on the active blocks
void grid_update(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const GridLayout& L = model.layout;
  GridFields& g = ws.grid;
  const std::vector<int>& active = ws.bins.active;
  const Vec3 dv_gravity = cfg.dt * cfg.gravity;
  const int np = static_cast<int>(model.primitives.size());
  parallel_for(team, static_cast<std::int64_t>(active.size()), kBlockGrain, [&](std::int64_t begin, std::int64_t end) {
    std::array<int, 3> lo, hi;
    for (std::int64_t bb = begin; bb < end; ++bb) {
      L.block_range(active[bb], lo, hi);
      for (int i = lo[0]; i < hi[0]; ++i)
        for (int j = lo[1]; j < hi[1]; ++j)
          for (int k = lo[2]; k < hi[2]; ++k) {
            const int n = L.node(i, j, k);
            if (!(g.m[n] > cfg.grid_mass_epsilon)) {
              g.v[n].setZero();
              continue;
            }
            // v = q / m + dt g
            Vec3 v = g.q[n] / g.m[n] + dv_gravity;
            const Vec3 x(i * cfg.dx, j * cfg.dx, k * cfg.dx);
            for (int pr = 0; pr < np; ++pr) v = collide(model.primitives[pr], ws.frames[pr], x, v);
            const int I[3] = {i, j, k};
            apply_boundary(cfg, I, v);
            g.v[n] = v;
          }
    }
  });
}

// 6. G2P and advection
void g2p(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const double dx = cfg.dx, inv_dx = 1.0 / dx;
  const GridLayout& L = model.layout;
  const GridFields& g = ws.grid;
  const double lo = cfg.clamp_low();
  const Vec3 hi(cfg.clamp_high(0), cfg.clamp_high(1), cfg.clamp_high(2));
  parallel_for(team, model.particles(), kParticleGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      Particle& P = ws.particles[p];
      const Stencil s = make_stencil(P.x, inv_dx, L.n);
      Vec3 v = Vec3::Zero();
      Mat3 B = Mat3::Zero();  // sum w v_i o^T with integer offsets o
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double wij = s.w[0][i] * s.w[1][j];
          const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
          for (int k = 0; k < 3; ++k) {
            const Vec3 wv = (wij * s.w[2][k]) * g.v[row + k];
            v += wv;
            B.col(0) += static_cast<double>(i) * wv;
            B.col(1) += static_cast<double>(j) * wv;
            B.col(2) += static_cast<double>(k) * wv;
          }
        }
      // C = (4 / dx^2) sum w v_i (x_i - x_p)^T = (4 / dx) (B - v fx^T)
      P.C = (4.0 * inv_dx) * (B - v * s.fx.transpose());
      P.v = v;
      // x += dt v, clamped to the domain
      const Vec3 x = P.x + cfg.dt * v;
      for (int a = 0; a < 3; ++a) P.x[a] = std::min(std::max(x[a], lo), hi[a]);
    }
  });
}

}  // namespace

namespace {

// The lower wall of axis a on velocity w (PlasticineLab's boundary): walls zero the outward
// component; the floor (a = y) applies Coulomb friction, |v_t| = sqrt(v_x^2 + v_z^2 + 1e-8),
// v = max(1 + mu v_y / |v_t|, 0) (v_x, 0, v_z), or sticks when mu >= 10. Sets `hit`.
Vec3 lower_wall(const MpmConfig& cfg, int a, const int I[3], const Vec3& w, bool& hit) {
  hit = I[a] < cfg.bound && w[a] < 0.0;
  if (!hit) return w;
  Vec3 v = w;
  if (a != 1 || cfg.floor_friction == 0.0) {
    v[a] = 0.0;
  } else if (cfg.floor_friction >= 10.0) {
    v.setZero();  // sticky floor
  } else {
    const double tn = std::sqrt(w.x() * w.x() + w.z() * w.z() + 1e-8);
    const double f = std::max(1.0 + cfg.floor_friction * w.y() / tn, 0.0);
    v = Vec3(f * w.x(), 0.0, f * w.z());
  }
  return v;
}

// the upper wall of axis a (PlasticineLab: index > n - bound) zeroes an outward component
bool upper_wall_hit(const MpmConfig& cfg, int a, const int I[3], const Vec3& v) {
  return I[a] > cfg.grid[a] - cfg.bound && v[a] > 0.0;
}

}  // namespace

void apply_boundary(const MpmConfig& cfg, const int I[3], Vec3& v) {
  for (int a = 0; a < 3; ++a) {
    bool hit;
    v = lower_wall(cfg, a, I, v, hit);
    if (upper_wall_hit(cfg, a, I, v)) v[a] = 0.0;
  }
}

Vec3 apply_boundary_adjoint(const MpmConfig& cfg, const int I[3], const Vec3& v_in, const Vec3& v_out_bar) {
  // forward again, keeping the velocity before each axis and after its lower wall
  Vec3 before[3], mid[3];
  bool lower[3];
  Vec3 v = v_in;
  for (int a = 0; a < 3; ++a) {
    before[a] = v;
    mid[a] = lower_wall(cfg, a, I, v, lower[a]);
    v = mid[a];
    if (upper_wall_hit(cfg, a, I, v)) v[a] = 0.0;
  }
  Vec3 bar = v_out_bar;
  for (int a = 2; a >= 0; --a) {
    if (upper_wall_hit(cfg, a, I, mid[a])) bar[a] = 0.0;
    if (!lower[a]) continue;
    const Vec3& w = before[a];
    if (a != 1 || cfg.floor_friction == 0.0) {
      bar[a] = 0.0;
    } else if (cfg.floor_friction >= 10.0) {
      bar.setZero();
    } else {
      const double mu = cfg.floor_friction;
      const double tn = std::sqrt(w.x() * w.x() + w.z() * w.z() + 1e-8);
      const double f = 1.0 + mu * w.y() / tn;
      if (f <= 0.0) {
        bar.setZero();
      } else {
        // v_h = f w_h (h = x, z): df/dw_y = mu / tn, df/dw_h = -mu w_y w_h / tn^3
        const double s = bar.x() * w.x() + bar.z() * w.z();
        const double t3 = tn * tn * tn;
        bar = Vec3(f * bar.x() - s * mu * w.y() * w.x() / t3, s * mu / tn, f * bar.z() - s * mu * w.y() * w.z() / t3);
      }
    }
  }
  return bar;
}

void substep(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions, SubstepTape* tape) {
  const MpmConfig& cfg = model.config;
  if (tape) {
    tape->before = ws.particles;
    tape->poses = ws.poses;
  }
  stress_phase(model, ws, team, tape);
  bin_particles(model, ws.bins, team, ws.particles);
  clear_blocks(model.layout, ws.bins.active, ws.grid);
  p2g(model, ws, team);
  // 4. kinematics pose f -> f + 1 and the contact frames
  const int np = static_cast<int>(model.primitives.size());
  for (int pr = 0; pr < np; ++pr) {
    const PrimitiveSpec& spec = model.primitives[pr];
    ws.next_poses[pr] = advance_pose(spec, ws.poses[pr], actions + model.action_offset(pr), cfg.substeps);
    ws.frames[pr] = contact_frame(spec, ws.poses[pr], ws.next_poses[pr], cfg.dt);
  }
  grid_update(model, ws, team);
  if (tape) tape->grid.save(model.layout, ws.bins.active, ws.grid);
  g2p(model, ws, team);
  for (int pr = 0; pr < np; ++pr) ws.poses[pr] = ws.next_poses[pr];
}

}  // namespace dsb::mpm
